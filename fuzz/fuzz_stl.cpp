// Fuzz target: the mesh reader on STL (harness/io/mesh_stl.cpp): binary (decided by the size its header declares) and
// ASCII (keywords in any case, several solids, polygon loops), corners welded exactly.
//
// Beyond the contract (fuzz_contract.hpp), what mesh_checks.hpp checks for every format: an
// accepted mesh is valid, its triangle passes repeat, its hash is that of the bytes, and memory,
// file and sniffed reads agree.
#include <cstddef>
#include <cstdint>

#include "mesh_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  bvhbench::fuzz::check_mesh_input(data, size, "stl");
  return 0;
}
