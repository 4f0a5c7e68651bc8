#pragma once
/// NumPy .npz archives: named .npy arrays in a ZIP (zip.hpp), as np.savez and
/// np.savez_compressed write them.
#include <map>
#include <string>
#include <string_view>

#include "npy.hpp"

namespace bvhbench {

/// Reads an .npz written by np.savez (stored entries; ZIP64 supported) or np.savez_compressed
/// (deflate). Keys drop ".npy"; members that are not .npy files are skipped, as np.load does.
/// Throws InputError for anything else, naming the file (and the entry, when the problem is in
/// one: a bad .npy, corrupt or truncated deflate data, a wrong size or CRC-32).
std::map<std::string, NpyArray> read_npz(const std::string& path);
/// The same for an .npz in memory; `name` names it in messages. `verify_crc` false skips the
/// entries' CRC-32 check (only for the fuzzer, see ZipReader).
std::map<std::string, NpyArray> parse_npz(std::string_view bytes, const std::string& name, bool verify_crc = true);
/// Writes an uncompressed .npz that np.load reads; atomically.
void write_npz(const std::string& path, const std::map<std::string, NpyArray>& arrays);

}  // namespace bvhbench
