// Fuzz target: the .npy reader (harness/io/npy.hpp: parse_npy / read_npy_from, parse_points_npy).
//
// Beyond the contract (fuzz_contract.hpp), an accepted array must keep what it promises
// (array_checks.hpp), and write back and read back to the same array when it is in C order; the
// c_only reader must refuse exactly the Fortran-order arrays. Accepted points must be finite.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "array_checks.hpp"
#include "fuzz_contract.hpp"
#include "harness/io/npy.hpp"

using namespace bvhbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const char* bytes = reinterpret_cast<const char*>(data);
  const std::string name = "fuzz.npy";
  NpyArray a;
  if (fuzz::accepts(name, [&] { a = parse_npy(bytes, size, name, NpyOrder::c_or_fortran); })) {
    fuzz::check_array(a, "the array");
    const bool c_order = fuzz::accepts(name, [&] { (void)parse_npy(bytes, size, name, NpyOrder::c_only); });
    fuzz::check(c_order == !a.fortran_order, "c_only refuses exactly the Fortran-order arrays");
    if (c_order) {
      const std::string again = npy_bytes(a);
      const NpyArray b = parse_npy(again.data(), again.size(), "again.npy");
      fuzz::check(b.dtype == a.dtype && b.shape == a.shape && b.data == a.data, "written and read back differs");
    }
  }
  std::vector<Vec3d> points;
  if (fuzz::accepts(name, [&] { points = parse_points_npy(bytes, size, name); }))
    for (const Vec3d& p : points)
      fuzz::check(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z), "a point is not finite");
  return 0;
}
