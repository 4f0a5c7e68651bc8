#pragma once
/// Loading a whole Mesh through the one streamed mesh reader (mesh_reader.hpp), and writing one.
#include <string>
#include <string_view>

#include "harness/core/mesh.hpp"
#include "harness/io/mesh_reader.hpp"

namespace bvhbench {

class Progress;

/// Reads a mesh file (format chosen by extension, case-insensitive; content sniffed if unknown).
/// Throws InputError naming the file and the problem for: a missing or unreadable file, an
/// unknown format, truncated data, element counts that do not match the data, a vertex index out
/// of range, a NaN or infinite coordinate, a face with fewer than 3 vertices, and an empty mesh
/// (no triangle). Degenerate and duplicate triangles are valid and kept.
/// `progress` (optional) is advanced over the file's bytes. The file is streamed, never mapped or
/// read whole: the peak memory is the mesh plus the reader's buffers (≈ 10 MiB; an STL's weld
/// table besides while it is read).
Mesh load_mesh(const std::string& path, Progress* progress = nullptr);

/// The same from bytes in memory (the same code; for fuzzing and tests): `name` names the input
/// in messages (and becomes Mesh::path), `format` is "ply", "obj", "stl", "off", a file name or
/// extension to take it from, or "" to sniff the content (an unknown format is an InputError).
Mesh load_mesh_bytes(std::string_view data, const std::string& name, const std::string& format = "");

/// The mesh's summary from one streamed pass over the file (the same checks and messages as
/// load_mesh; equal to load_mesh(path).summary()), holding only the reader's buffers.
MeshSummary summarize_mesh(const std::string& path, Progress* progress = nullptr);

/// Reads every vertex and triangle of `reader` into a Mesh (path = the reader's name).
Mesh read_mesh(MeshReader& reader);

/// Writes a binary little-endian PLY (float32 coordinates, int32 indices). For tests and tools.
void write_ply(const std::string& path, const Mesh& mesh, bool ascii = false);

}  // namespace bvhbench
