// The float vertices in a temporary file behind a page cache (vertex_pages.hpp).
#include "methods/ebp_octree/build/vertex_pages.hpp"

#include <cstring>
#include <stdexcept>
#include <string>

namespace ebp {

namespace {
constexpr std::size_t kVertexBytes = 3 * sizeof(float);
}  // namespace

VertexPages::VertexPages(const std::string& dir, std::uint64_t vertices, std::size_t cache_bytes)
    : dir_(dir),
      vertices_(vertices),
      cache_bytes_(cache_bytes),
      file_(std::make_unique<bvhbench::ScratchFile>(dir, "vertices", kVertexBytes, cache_bytes)) {}

void VertexPages::append(const float* xyz, std::size_t n) { file_->append(xyz, n); }

void VertexPages::rewind() {
  // A new file: the old one is closed, and with it gone.
  file_ = std::make_unique<bvhbench::ScratchFile>(dir_, "vertices", kVertexBytes, cache_bytes_);
}

void VertexPages::finish() {
  if (file_->size() != vertices_)
    throw std::logic_error("VertexPages: " + std::to_string(file_->size()) + " vertices written, " +
                           std::to_string(vertices_) + " announced");
  file_->finish();
}

void VertexPages::gather(const std::uint32_t* idx, std::size_t n, float* xyz) {
  for (std::size_t k = 0; k < n; ++k) std::memcpy(xyz + 3 * k, file_->record(idx[k]), kVertexBytes);
}

}  // namespace ebp
