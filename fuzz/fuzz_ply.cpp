// Fuzz target: the mesh reader on PLY (harness/io/mesh_ply.cpp): ASCII and binary of either byte order, any elements and
// property types, `face` lists and `tristrips` with restarts, in any element order.
//
// Beyond the contract (fuzz_contract.hpp), what mesh_checks.hpp checks for every format: an
// accepted mesh is valid, its triangle passes repeat, its hash is that of the bytes, and memory,
// file and sniffed reads agree.
#include <cstddef>
#include <cstdint>

#include "mesh_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  bvhbench::fuzz::check_mesh_input(data, size, "ply");
  return 0;
}
