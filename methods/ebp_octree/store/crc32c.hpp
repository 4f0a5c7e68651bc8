#pragma once
/// The checksum of every section and page of a `.ebp` store (format.hpp).
#include <cstddef>
#include <cstdint>

namespace ebp {

/// CRC-32C (Castagnoli), hardware (SSE 4.2) when the CPU has it.
std::uint32_t crc32c(const void* data, std::size_t n, std::uint32_t crc = 0);

}  // namespace ebp
