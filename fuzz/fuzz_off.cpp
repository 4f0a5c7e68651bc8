// Fuzz target: the mesh reader on OFF (harness/io/mesh_off.cpp): every keyword variant, counts on the keyword line or
// the next, ModelNet's glued counts, extras on vertex and face lines, comments.
//
// Beyond the contract (fuzz_contract.hpp), what mesh_checks.hpp checks for every format: an
// accepted mesh is valid, its triangle passes repeat, its hash is that of the bytes, and memory,
// file and sniffed reads agree.
#include <cstddef>
#include <cstdint>

#include "mesh_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  bvhbench::fuzz::check_mesh_input(data, size, "off");
  return 0;
}
