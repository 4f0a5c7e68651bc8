#include "harness/io/oracle_file.hpp"

#include <map>

#include "harness/io/npz.hpp"

namespace bvhbench {

void write_oracle_npz(const std::string& path, const OracleAnswers& a, const std::string& mesh_sha256,
                      const std::string& queries_sha256) {
  std::map<std::string, NpyArray> z;
  z["inside"] = NpyArray::b1(a.inside);
  z["winding"] = NpyArray::f8(a.winding);
  z["distance"] = NpyArray::f8(a.distance);
  z["closest"] = NpyArray::f8_n3(a.closest);
  z["normal"] = NpyArray::f8_n3(a.normal);
  z["triangle"] = NpyArray::i8(a.triangle);
  z["tie_count"] = NpyArray::i8(a.tie_count);
  NpyArray tied = NpyArray::i8(a.tied);
  tied.shape = {a.triangle.size(), std::size_t(kMaxTied)};
  z["tied_triangles"] = tied;
  z["tie_tolerance"] = NpyArray::f8({a.tie_tolerance});
  z["boundary_edges"] = NpyArray::i8({std::int64_t(a.boundary_edges)});
  z["definition"] = NpyArray::unicode(a.definition);
  // What each definition of inside needs (core/oracle.hpp): the parity per point, the edge
  // counts the methods' contracts are checked against, and the definitions defined here.
  z["parity"] = NpyArray::b1(a.parity);
  z["odd_edges"] = NpyArray::i8({std::int64_t(a.odd_edges)});
  z["nonmanifold_edges"] = NpyArray::i8({std::int64_t(a.nonmanifold_edges)});
  z["solid_boundary_edges"] = NpyArray::i8({std::int64_t(a.solid_boundary_edges)});
  std::string defined;
  for (const std::string& d : a.definitions) defined += (defined.empty() ? "" : ",") + d;
  z["definitions"] = NpyArray::unicode(defined);
  z["mesh_sha256"] = NpyArray::unicode(mesh_sha256);
  z["queries_sha256"] = NpyArray::unicode(queries_sha256);
  write_npz(path, z);
}

}  // namespace bvhbench
