// Loading a Mesh through the one mesh reader (mesh_reader.hpp; the formats are parsed in
// mesh_ply.cpp, mesh_obj.cpp, ...), and a PLY writer.
#include "harness/io/mesh_io.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "harness/util/atomic_file.hpp"

namespace bvhbench {

namespace {
constexpr std::size_t kChunk = std::size_t(8) << 20;
constexpr bool kBigEndianHost = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;
}  // namespace

Mesh read_mesh(MeshReader& reader) {
  Mesh mesh;
  mesh.path = reader.name();
  // The hints are bounded by the file's size (checked by the parser), so reserving them is safe.
  mesh.vertices.reserve(std::size_t(reader.num_vertices()));
  reader.read_vertices([&](std::uint64_t, const Vec3d* v, std::size_t n) {
    mesh.vertices.insert(mesh.vertices.end(), v, v + n);
  });
  mesh.triangles.reserve(std::size_t(reader.num_triangles()));
  reader.read_triangles([&](std::uint64_t, const Triangle* t, std::size_t n) {
    mesh.triangles.insert(mesh.triangles.end(), t, t + n);
  });
  mesh.sha256 = reader.sha256();
  mesh.file = reader.info();
  return mesh;
}

Mesh load_mesh(const std::string& path, Progress* progress) {
  auto reader = MeshReader::open(path, progress);
  return read_mesh(*reader);
}

MeshSummary summarize_mesh(const std::string& path, Progress* progress) {
  auto reader = MeshReader::open(path, progress);
  MeshSummary s;
  s.path = reader->name();
  reader->read_vertices([&](std::uint64_t, const Vec3d* v, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) s.bounds.add(v[i]);
  });
  reader->read_triangles([](std::uint64_t, const Triangle*, std::size_t) {});  // checks them, completes the hash
  s.vertices = reader->num_vertices();
  s.triangles = reader->num_triangles();
  s.sha256 = reader->sha256();
  return s;
}

Mesh load_mesh_bytes(std::string_view data, const std::string& name, const std::string& format) {
  auto reader = MeshReader::open_bytes(data, name, format);
  return read_mesh(*reader);
}

// ---------------------------------------------------------------------------------------------
// Writer.
// ---------------------------------------------------------------------------------------------
void write_ply(const std::string& path, const Mesh& mesh, bool ascii) {
  AtomicOutputFile f(path);
  std::string buf;
  buf.reserve(kChunk + 256);
  auto flush = [&](bool force) {
    if (buf.size() >= kChunk || (force && !buf.empty())) {
      f.write(buf);
      buf.clear();
    }
  };
  buf += "ply\nformat ";
  buf += ascii ? "ascii" : "binary_little_endian";
  buf += " 1.0\ncomment written by bvhbench\nelement vertex " + std::to_string(mesh.vertices.size()) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
         std::to_string(mesh.triangles.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  char tmpc[64];
  for (const Vec3d& v : mesh.vertices) {
    const float c[3] = {float(v.x), float(v.y), float(v.z)};
    if (ascii) {
      for (int k = 0; k < 3; ++k) {
        auto r = std::to_chars(tmpc, tmpc + sizeof tmpc, c[k]);
        buf.append(tmpc, r.ptr);
        buf += k < 2 ? ' ' : '\n';
      }
    } else {
      char b[12];
      for (int k = 0; k < 3; ++k) {
        std::uint32_t u;
        std::memcpy(&u, &c[k], 4);
        if (kBigEndianHost) u = __builtin_bswap32(u);
        std::memcpy(b + 4 * k, &u, 4);
      }
      buf.append(b, 12);
    }
    flush(false);
  }
  for (const auto& t : mesh.triangles) {
    if (ascii) {
      buf += "3";
      for (int k = 0; k < 3; ++k) {
        buf += ' ';
        auto r = std::to_chars(tmpc, tmpc + sizeof tmpc, t[k]);
        buf.append(tmpc, r.ptr);
      }
      buf += '\n';
    } else {
      char b[13];
      b[0] = 3;
      for (int k = 0; k < 3; ++k) {
        std::uint32_t u = t[k];
        if (kBigEndianHost) u = __builtin_bswap32(u);
        std::memcpy(b + 1 + 4 * k, &u, 4);
      }
      buf.append(b, 13);
    }
    flush(false);
  }
  flush(true);
  f.commit();
}

}  // namespace bvhbench
