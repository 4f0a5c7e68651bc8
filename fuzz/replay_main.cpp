// The replay driver: a main() for a fuzz target built without libFuzzer (the normal GCC build),
// so that `make test` runs every target over its seed corpus and its regressions (fuzz/README.md).
//
//   fuzz_npy_replay DIR_OR_FILE...
//
// Feeds every regular file under each argument (folders recursively, in sorted order) to
// LLVMFuzzerTestOneInput. Exit 0 when every input passed the target's contract, 1 when one
// threw (the file is named), 2 on bad usage or when no input was found at all (an empty corpus
// would otherwise pass without checking anything). A contract violation aborts, naming itself.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: " << argv[0] << " DIR_OR_FILE...\n";
    return 2;
  }
  std::vector<fs::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const fs::path p(argv[i]);
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) {
      inputs.push_back(p);
    } else if (fs::is_directory(p, ec)) {
      std::vector<fs::path> found;
      for (const auto& e : fs::recursive_directory_iterator(p))
        if (e.is_regular_file() && e.path().filename().string()[0] != '.') found.push_back(e.path());
      std::sort(found.begin(), found.end());
      inputs.insert(inputs.end(), found.begin(), found.end());
    } else {
      std::cerr << p.string() << ": no such file or folder\n";
      return 2;
    }
  }
  if (inputs.empty()) {
    std::cerr << "no inputs found\n";
    return 2;
  }
  for (const fs::path& p : inputs) {
    std::ifstream f(p, std::ios::binary);
    if (!f) {
      std::cerr << p.string() << ": cannot read\n";
      return 2;
    }
    const std::vector<char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    // A copy of exactly `size` bytes, as libFuzzer passes them: a read past the end is a
    // finding under a sanitizer build, never a silent read of the next file's bytes.
    const std::vector<std::uint8_t> data(bytes.begin(), bytes.end());
    try {
      LLVMFuzzerTestOneInput(data.data(), data.size());
    } catch (const std::exception& e) {
      std::cerr << p.string() << ": the target threw " << e.what() << "\n";
      return 1;
    } catch (...) {
      std::cerr << p.string() << ": the target threw a non-standard exception\n";
      return 1;
    }
  }
  std::cout << inputs.size() << " inputs replayed, every one within the contract\n";
  return 0;
}
