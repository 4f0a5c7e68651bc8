#pragma once
/// Text files of points (.xyz, .csv): one point a line, in the file's order, as other tools
/// write them (recorded probe paths, point clouds with normals).
///
/// - Values are separated by commas (a line with a comma is split at commas, each field trimmed
///   of spaces and tabs) or else by runs of spaces and tabs. Numbers are decimal or scientific
///   with an optional sign, read exactly (17 significant digits give the same double back).
/// - Blank lines are skipped; `#` starts a comment that runs to the end of the line, on a line of
///   its own or after the values. A UTF-8 byte-order mark at the start is skipped; lines may end
///   in CRLF.
/// - The first line that is neither blank nor a comment is a header (`x,y,z`, `X Y Z nx ny nz`)
///   and skipped when none of its fields is a number.
/// - The first point line sets the number of columns (at least 3): x, y, z are the first three;
///   further columns (normals, colours, labels) are ignored, but every point line must have as
///   many, so that two lines run together are not read as one point.
/// Refused, as InputError naming the file and the line: a value that is not a number, a missing
/// or empty value, a column count that differs from the first point's, a NaN or infinite
/// coordinate, a line longer than 64 KiB; and a file with no point at all.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "geometry.hpp"

namespace bvhbench {

/// The points of the text file at `path`, in order (N x 3, as written).
std::vector<Vec3d> read_points_text(const std::string& path);
/// The same for text in memory; `name` names it in messages. The text is split into lines in
/// pieces of `piece_bytes` (as a file is read), so that a test can make lines straddle pieces:
/// the points and the errors do not depend on it.
std::vector<Vec3d> parse_points_text(std::string_view text, const std::string& name,
                                     std::size_t piece_bytes = std::size_t(1) << 20);

}  // namespace bvhbench
