// `bvhbench mesh-info M [--json]`: what the reader read from a mesh file, as every other command
// reads it (load_mesh), and what the mesh is (mesh_stats.hpp).
#include <charconv>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "harness/cli/commands.hpp"
#include "harness/core/mesh.hpp"
#include "harness/core/mesh_stats.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/util/printable.hpp"

namespace bvhbench {

namespace {

/// Shortest text that reads back as exactly `v`.
std::string exact(double v) {
  char b[32];
  const auto r = std::to_chars(b, b + sizeof b, v);
  return std::string(b, r.ptr);
}

std::string point(const Vec3d& p) { return "(" + exact(p.x) + ", " + exact(p.y) + ", " + exact(p.z) + ")"; }

std::string format_title(const MeshFileInfo& f) {
  if (f.format == "ply") return "PLY (" + f.variant + ")";
  if (f.format == "stl") return "STL (" + f.variant + ")";
  if (f.format == "off") return "OFF (" + f.variant + ")";
  return "OBJ";
}

nlohmann::json info_json(const Mesh& m, const MeshStats& s) {
  const MeshFileInfo& f = m.file;
  nlohmann::json j;
  j["path"] = printable(m.path);
  j["format"] = f.format;
  j["variant"] = f.variant;
  j["sha256"] = m.sha256;
  j["vertices"] = m.vertices.size();
  j["triangles"] = m.triangles.size();
  j["polygons"] = f.polygons;
  j["polygons_triangulated"] = f.polygons_triangulated;
  j["strips"] = f.strips;
  j["strip_joins_dropped"] = f.strip_joins_dropped;
  j["stl_corners"] = f.corners;
  j["stl_solids"] = f.solids;
  j["bounds"] = {{"min", {s.bounds.lo.x, s.bounds.lo.y, s.bounds.lo.z}},
                 {"max", {s.bounds.hi.x, s.bounds.hi.y, s.bounds.hi.z}}};
  j["closed"] = s.closed();
  j["edges"] = s.edges;
  j["boundary_edges"] = s.boundary_edges;
  j["nonmanifold_edges"] = s.nonmanifold_edges;
  j["misoriented_edges"] = s.misoriented_edges;
  j["edges_balanced"] = s.balanced();
  j["degenerate_triangles"] = s.degenerate_triangles;
  j["unreferenced_vertices"] = s.unreferenced_vertices;
  return j;
}

void print_info(const Mesh& m, const MeshStats& s) {
  const MeshFileInfo& f = m.file;
  auto row = [](const char* key, const std::string& value) { std::printf("%-12s %s\n", key, value.c_str()); };
  row("mesh", printable(m.path));
  row("format", format_title(f));
  row("sha256", m.sha256);
  std::string v = std::to_string(m.vertices.size());
  if (f.format == "stl") v += " (welded from " + std::to_string(f.corners) + " facet corners)";
  if (s.unreferenced_vertices) v += ", " + std::to_string(s.unreferenced_vertices) + " used by no triangle";
  row("vertices", v);
  row("triangles", std::to_string(m.triangles.size()));
  row("polygons", std::to_string(f.polygons) + " in the file, " + std::to_string(f.polygons_triangulated) +
                      " of more than 3 vertices fan-triangulated");
  if (f.strips || f.strip_joins_dropped)
    row("strips", std::to_string(f.strips) + ", " + std::to_string(f.strip_joins_dropped) +
                      " joins dropped (strip triangles with a repeated vertex)");
  if (f.format == "stl" && f.variant == "ascii") row("solids", std::to_string(f.solids) + " (read as one mesh)");
  row("bounds", point(s.bounds.lo) + " .. " + point(s.bounds.hi));
  if (s.closed())
    row("closed", "yes: every edge is used by exactly two triangles, once in each direction");
  else
    row("closed", "no: " + std::to_string(s.boundary_edges) + " boundary, " + std::to_string(s.nonmanifold_edges) +
                      " non-manifold, " + std::to_string(s.misoriented_edges) + " misoriented of " +
                      std::to_string(s.edges) + " edges" +
                      (s.balanced() ? " (but every edge is used as often in each direction: the oracle's "
                                      "exact inside applies)"
                                    : ""));
  row("degenerate", std::to_string(s.degenerate_triangles) +
                        " triangles (a repeated vertex or collinear corners: zero area, kept)");
}

}  // namespace

void add_mesh_info_command(CLI::App& app) {
  struct Opts {
    std::string mesh;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = app.add_subcommand("mesh-info", "Show what is read from a mesh file (format, counts, bounds, "
                                              "closed or not, degenerate triangles, strip joins, sha256)");
  cmd->add_option("mesh", o->mesh, "Mesh file (PLY, OBJ, STL, OFF)")->required();
  cmd->add_flag("--json", o->json, "Machine-readable output");
  cmd->callback([o] {
    const Mesh m = load_mesh(o->mesh);
    const MeshStats s = mesh_stats(m);
    if (o->json)
      std::cout << info_json(m, s).dump(2) << "\n";
    else
      print_info(m, s);
  });
}

}  // namespace bvhbench
