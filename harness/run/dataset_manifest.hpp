#pragma once
/// What the dataset manifest says of a mesh (datasets-scripts/make_datasets.py writes
/// manifest.json beside the meshes of a preset): how it was made, and whether it is a stress
/// case. A result records it (job.mesh.dataset), so that the report knows a stress case from how
/// the mesh was made rather than guessing from its file name.
#include <string>

#include <nlohmann/json.hpp>

namespace bvhbench {

/// {"family", "kind", "manifest", and "closed" when it says} of the entry of `mesh_path`'s folder's manifest.json whose file
/// is that mesh and whose sha256 is `sha256` (so that the manifest describes these very bytes);
/// null when there is no manifest, it cannot be read, or it has no such entry.
nlohmann::json dataset_entry(const std::string& mesh_path, const std::string& sha256);

}  // namespace bvhbench
