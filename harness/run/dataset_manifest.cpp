// The dataset manifest's entry of a mesh (dataset_manifest.hpp).
#include "harness/run/dataset_manifest.hpp"

#include <filesystem>
#include <fstream>
#include <iterator>

#include "harness/util/printable.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace bvhbench {

json dataset_entry(const std::string& mesh_path, const std::string& sha256) {
  const fs::path mesh(mesh_path);
  const fs::path manifest = mesh.parent_path() / "manifest.json";
  std::ifstream f(manifest, std::ios::binary);
  if (!f || sha256.empty()) return nullptr;
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  // A manifest that cannot be read says nothing of the mesh; the job does not depend on it.
  const json doc = json::parse(text, nullptr, false);
  if (!doc.is_object() || !doc.contains("meshes") || !doc["meshes"].is_array()) return nullptr;
  const std::string file = mesh.filename().string();
  for (const json& e : doc["meshes"]) {
    if (!e.is_object() || e.value("file", std::string()) != file || e.value("sha256", std::string()) != sha256)
      continue;
    const json& kind = e.contains("kind") ? e["kind"] : json();
    const json& family = e.contains("family") ? e["family"] : json();
    if (!kind.is_string() || !family.is_string()) return nullptr;
    json out = {{"kind", printable(kind.get<std::string>())},
                {"family", printable(family.get<std::string>())},
                {"manifest", printable(manifest.string())}};
    if (e.contains("closed") && e["closed"].is_boolean()) out["closed"] = e["closed"];
    return out;
  }
  return nullptr;
}

}  // namespace bvhbench
