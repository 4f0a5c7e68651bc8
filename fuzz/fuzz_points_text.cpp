// Fuzz target: the text points reader (harness/points_text.hpp: .xyz / .csv).
//
// Beyond the contract (fuzz_contract.hpp): the text is read once in one piece and once in small
// pieces (1 to 64 bytes, chosen by the input's length), as a file larger than the reader's
// buffer is; both must give the same points or the same refusal, since where a line straddles
// two pieces must not matter. Accepted points must be finite.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "fuzz_contract.hpp"
#include "points_text.hpp"

using namespace bvhbench;

namespace {

/// The points, or the refusal's message.
struct Outcome {
  std::vector<Vec3d> points;
  std::optional<std::string> error;
};

Outcome read(std::string_view text, const std::string& name, std::size_t piece) {
  Outcome o;
  o.error = fuzz::refusal(name, [&] { o.points = parse_points_text(text, name, piece); });
  return o;
}

bool same(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!(a[i].x == b[i].x && a[i].y == b[i].y && a[i].z == b[i].z)) return false;
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string name = "fuzz.xyz";
  const std::string_view text = fuzz::as_text(data, size);
  const Outcome whole = read(text, name, std::size_t(1) << 20);
  const Outcome pieces = read(text, name, 1 + size % 64);
  fuzz::check(whole.error == pieces.error,
              "whole: '" + whole.error.value_or("accepted") + "', in pieces: '" + pieces.error.value_or("accepted") + "'");
  fuzz::check(same(whole.points, pieces.points), "the points differ when read in pieces");
  for (const Vec3d& p : whole.points)
    fuzz::check(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z), "a point is not finite");
  return 0;
}
