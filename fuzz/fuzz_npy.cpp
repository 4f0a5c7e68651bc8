// Fuzz target: the .npy reader (harness/io/npy.hpp: parse_npy / read_npy_from, parse_points_npy).
//
// Beyond the contract (fuzz_contract.hpp), an accepted array must be what its header says (data
// of product(shape) * itemsize bytes, kept little-endian), must write back and read back to the
// same array when it is in C order, and its unicode strings must be valid UTF-8 (they end up in
// result JSON). Accepted points must be finite.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include <nlohmann/json.hpp>

#include "fuzz_contract.hpp"
#include "harness/io/npy.hpp"

using namespace bvhbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const char* bytes = reinterpret_cast<const char*>(data);
  const std::string name = "fuzz.npy";
  NpyArray a;
  if (fuzz::accepts(name, [&] { a = parse_npy(bytes, size, name, NpyOrder::c_or_fortran); })) {
    fuzz::check(a.data.size() == a.size() * a.itemsize(), "data size is not product(shape) * itemsize");
    fuzz::check(a.dtype[0] == '<' || a.dtype[0] == '|', "dtype " + a.dtype + " is not in our byte order");
    if (a.dtype[1] == 'U')
      for (std::size_t i = 0; i < std::min<std::size_t>(a.size(), 64); ++i) (void)nlohmann::json(a.unicode_value(i)).dump();
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
