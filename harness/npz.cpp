// .npz = ZIP of .npy entries: each entry is read by the .npy reader straight from the ZIP entry
// reader (which inflates deflated entries as it goes), so an array is never copied whole.
#include "npz.hpp"

#include "errors.hpp"
#include "zip.hpp"

namespace bvhbench {

namespace {

std::map<std::string, NpyArray> read_arrays(ZipReader& zip) {
  const std::string& path = zip.path();
  std::map<std::string, NpyArray> out;
  for (const ZipEntry& z : zip.entries()) {
    if (!z.name.empty() && z.name.back() == '/') continue;  // a directory
    std::string key = z.name;
    if (key.size() > 4 && key.compare(key.size() - 4, 4, ".npy") == 0) key.resize(key.size() - 4);
    else continue;  // np.load only exposes .npy members as arrays
    if (out.count(key)) throw file_error(path, "duplicate entry " + quoted_excerpt(z.name, 100));
    ZipReader::EntryReader entry = zip.open(z);
    // A deflated entry's plain size is only what the directory says (zip.hpp bounds it to ~1000x
    // the compressed size): the array grows as it inflates rather than being allocated for it.
    NpyArray a = read_npy_from([&](void* dst, std::size_t n) { entry.read(dst, n); }, entry.size(), entry.where(),
                               NpyOrder::c_only, z.method == 8 ? NpySize::claimed : NpySize::present);
    entry.finish();
    out.emplace(key, std::move(a));
  }
  return out;
}

}  // namespace

std::map<std::string, NpyArray> read_npz(const std::string& path) {
  ZipReader zip(path);
  return read_arrays(zip);
}

std::map<std::string, NpyArray> parse_npz(std::string_view bytes, const std::string& name, bool verify_crc) {
  ZipReader zip(bytes, name, verify_crc);
  return read_arrays(zip);
}

void write_npz(const std::string& path, const std::map<std::string, NpyArray>& arrays) {
  std::map<std::string, std::string> headers;  // checks every array before the file is begun
  for (const auto& kv : arrays) headers[kv.first] = npy_header(kv.second);
  ZipWriter zip(path);
  for (const auto& kv : arrays) {
    const std::string& head = headers[kv.first];
    zip.add_stored(kv.first + ".npy", {{head.data(), head.size()}, {kv.second.data.data(), kv.second.data.size()}});
  }
  zip.commit();
}

}  // namespace bvhbench
