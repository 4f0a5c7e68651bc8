// Fuzz target: the mesh reader on OBJ (harness/io/mesh_obj.cpp): `v`, `f` / `fo` in every index form, relative indices,
// polygons, comments and `\\` continuations, read in two passes (vertices, then faces).
//
// Beyond the contract (fuzz_contract.hpp), what mesh_checks.hpp checks for every format: an
// accepted mesh is valid, its triangle passes repeat, its hash is that of the bytes, and memory,
// file and sniffed reads agree.
#include <cstddef>
#include <cstdint>

#include "mesh_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  bvhbench::fuzz::check_mesh_input(data, size, "obj");
  return 0;
}
