#pragma once
/// What the mesh reader promises for any bytes (fuzz_ply.cpp, fuzz_obj.cpp, fuzz_stl.cpp,
/// fuzz_off.cpp; harness/io/mesh_reader.hpp): beyond the contract (fuzz_contract.hpp), an input
/// it accepts
/// - has finite coordinates and vertex indices below the vertex count;
/// - comes in contiguous chunks of at most 64 Ki items, and every triangle pass delivers the
///   same triangles in the same chunks, with the same counts (polygons, strips, ...);
/// - has the SHA-256 of its bytes;
/// and before the first pass, the reader's counts for reserving memory are bounded by the
/// input's size (at most one vertex and one triangle per byte, and 3 more vertices), so that a
/// lying header cannot make `read_mesh` reserve more than ~36 bytes per input byte.
///
/// Each input is read three ways, which must agree: through the reader's passes from memory,
/// as a file (`load_mesh`, a temporary file of this process with the format's extension: the
/// buffered file path of ByteSource), and from memory with the format sniffed
/// (`load_mesh_bytes(..., "")`), which must read it as the explicit format does whenever it
/// takes it for that format. All three give the input the temporary file's path as its name, so
/// that their messages compare equal.
#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "fuzz_contract.hpp"
#include "harness/core/mesh.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/io/mesh_reader.hpp"
#include "harness/util/sha256.hpp"

namespace bvhbench::fuzz {

/// One read: the mesh, or the refusal's message.
struct MeshOutcome {
  Mesh mesh;
  std::optional<std::string> error;
};

inline bool same_info(const MeshFileInfo& a, const MeshFileInfo& b) {
  return a.format == b.format && a.variant == b.variant && a.polygons == b.polygons &&
         a.polygons_triangulated == b.polygons_triangulated && a.strips == b.strips &&
         a.strip_joins_dropped == b.strip_joins_dropped && a.corners == b.corners && a.solids == b.solids;
}

/// Bit for bit: the same coordinates (a -0.0 is not a 0.0), triangles, hash and file info.
inline bool same_mesh(const Mesh& a, const Mesh& b) {
  return a.vertices.size() == b.vertices.size() &&
         (a.vertices.empty() || std::memcmp(a.vertices.data(), b.vertices.data(), a.vertices.size() * sizeof(Vec3d)) == 0) &&
         a.triangles == b.triangles && a.sha256 == b.sha256 && same_info(a.file, b.file);
}

inline std::string outcome_text(const MeshOutcome& o) {
  return o.error ? "refused: " + *o.error
                 : "accepted: " + std::to_string(o.mesh.vertices.size()) + " vertices, " +
                       std::to_string(o.mesh.triangles.size()) + " triangles";
}

inline void check_same(const MeshOutcome& a, const MeshOutcome& b, const std::string& how_a, const std::string& how_b) {
  const bool same = a.error ? a.error == b.error : !b.error && same_mesh(a.mesh, b.mesh);
  check(same, how_a + " " + outcome_text(a) + "; " + how_b + " " + outcome_text(b));
}

/// Finite coordinates, indices below the vertex count. `what` prefixes a violation.
inline void check_valid(const Mesh& m, const std::string& what) {
  for (const Vec3d& v : m.vertices)
    check(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z), what + "a vertex is not finite");
  for (const Triangle& t : m.triangles)
    for (std::uint32_t i : t) check(i < m.vertices.size(), what + "a vertex index is out of range");
}

/// Checks the chunks of one pass: contiguous from 0, each of 1 to 64 Ki items. Records them.
class ChunkLog {
 public:
  void add(std::uint64_t first, std::size_t n, const char* what) {
    check(first == total_, std::string(what) + " chunk starts at " + std::to_string(first) + ", not at " +
                               std::to_string(total_));
    check(n >= 1 && n <= (std::size_t(1) << 16), std::string(what) + " chunk of " + std::to_string(n) + " items");
    sizes_.push_back(n);
    total_ += n;
  }
  std::uint64_t total() const { return total_; }
  const std::vector<std::size_t>& sizes() const { return sizes_; }

 private:
  std::uint64_t total_ = 0;
  std::vector<std::size_t> sizes_;
};

/// Reads `bytes` through MeshReader's passes (three of the triangles), checking what they promise
/// against each other and against the bytes.
inline MeshOutcome read_by_passes(std::string_view bytes, const std::string& name, const std::string& format) {
  MeshOutcome o;
  std::unique_ptr<MeshReader> reader;
  ChunkLog vchunks, tchunks;
  o.error = refusal(name, [&] {
    reader = MeshReader::open_bytes(bytes, name, format);
    // The counts read_mesh reserves before the passes (checked against the input's size).
    check(reader->num_vertices() <= bytes.size() + 3,
          "the vertex count for reserving is " + std::to_string(reader->num_vertices()) + " for " +
              std::to_string(bytes.size()) + " bytes");
    check(reader->num_triangles() <= bytes.size(),
          "the triangle count for reserving is " + std::to_string(reader->num_triangles()) + " for " +
              std::to_string(bytes.size()) + " bytes");
    reader->read_vertices([&](std::uint64_t first, const Vec3d* v, std::size_t n) {
      vchunks.add(first, n, "vertex");
      o.mesh.vertices.insert(o.mesh.vertices.end(), v, v + n);
    });
    reader->read_triangles([&](std::uint64_t first, const Triangle* t, std::size_t n) {
      tchunks.add(first, n, "triangle");
      o.mesh.triangles.insert(o.mesh.triangles.end(), t, t + n);
    });
  });
  if (o.error) return o;
  o.mesh.path = name;
  o.mesh.sha256 = reader->sha256();
  o.mesh.file = reader->info();
  check(reader->num_vertices() == o.mesh.vertices.size() && vchunks.total() == o.mesh.vertices.size(),
        "num_vertices() is not the vertices delivered");
  check(reader->num_triangles() == o.mesh.triangles.size(), "num_triangles() is not the triangles delivered");
  check(o.mesh.sha256 == sha256_hex(bytes.data(), bytes.size()), "sha256() is not the SHA-256 of the bytes");
  check_valid(o.mesh, "");
  for (int pass = 2; pass <= 3; ++pass) {
    std::size_t at = 0;
    ChunkLog again;
    try {
      reader->read_triangles([&](std::uint64_t first, const Triangle* t, std::size_t n) {
        again.add(first, n, "triangle");
        for (std::size_t j = 0; j < n; ++j, ++at)
          check(at < o.mesh.triangles.size() && t[j] == o.mesh.triangles[at],
                "triangle pass " + std::to_string(pass) + " differs at triangle " + std::to_string(at));
      });
    } catch (const InputError& e) {
      violated("triangle pass " + std::to_string(pass) + " refused what the first accepted: " + e.what());
    }
    check(again.sizes() == tchunks.sizes(), "triangle pass " + std::to_string(pass) + " has other chunks");
    check(same_info(reader->info(), o.mesh.file), "triangle pass " + std::to_string(pass) + " counts otherwise");
    check(reader->sha256() == o.mesh.sha256, "the hash changed in pass " + std::to_string(pass));
  }
  return o;
}

/// This process's temporary mesh file, with extension `ext` (".ply": a process checks one
/// format, the extension of the first call stays), removed at exit.
inline const std::string& temp_mesh_path(const std::string& ext) {
  static const std::string path = [&] {
    std::string p = (std::filesystem::temp_directory_path() / ("fuzz_mesh_XXXXXX" + ext)).string();
    const int fd = ::mkstemps(p.data(), int(ext.size()));
    if (fd < 0) violated("cannot make a temporary file " + p);
    ::close(fd);
    static const std::string removed_at_exit = p;
    std::atexit([] { std::remove(removed_at_exit.c_str()); });
    return p;
  }();
  return path;
}

/// Replaces the contents of the file at `path` with the bytes. Written over in place and cut to
/// size, never truncated to 0 first: on ext4, a file truncated to 0 and written is flushed to the
/// disk when it is closed (auto_da_alloc), which made every input take milliseconds.
inline void write_temp_file(const std::string& path, const std::uint8_t* data, std::size_t size) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  bool ok = fd >= 0;
  for (std::size_t at = 0; ok && at < size;) {
    const ssize_t w = ::pwrite(fd, data + at, size - at, off_t(at));
    ok = w > 0;
    at += ok ? std::size_t(w) : 0;
  }
  if (ok) ok = ::ftruncate(fd, off_t(size)) == 0;
  if (fd >= 0) ok = ::close(fd) == 0 && ok;
  if (!ok) violated("cannot write " + path);
}

/// The whole check of one input, read as `format` ("ply", "obj", "stl", "off").
inline void check_mesh_input(const std::uint8_t* data, std::size_t size, const std::string& format) {
  const std::string& path = temp_mesh_path("." + format);
  const std::string_view bytes = as_text(data, size);
  const MeshOutcome passes = read_by_passes(bytes, path, format);

  write_temp_file(path, data, size);
  MeshOutcome file;
  file.error = refusal(path, [&] { file.mesh = load_mesh(path); });
  check_same(passes, file, "from memory", "as a file");

  MeshOutcome sniffed;
  sniffed.error = refusal(path, [&] { sniffed.mesh = load_mesh_bytes(bytes, path, ""); });
  if (!sniffed.error && sniffed.mesh.file.format == format) check_same(passes, sniffed, "as " + format, "sniffed");
  if (!sniffed.error && sniffed.mesh.file.format != format) check_valid(sniffed.mesh, "sniffed as " + sniffed.mesh.file.format + ": ");
}

}  // namespace bvhbench::fuzz
