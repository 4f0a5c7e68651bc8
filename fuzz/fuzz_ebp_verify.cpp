// Fuzz target: `bvhbench ebp verify`, the whole-store check of a `.ebp`
// (methods/ebp_octree/ebp_verify.hpp: verify_store). It takes a path, so each input is written to
// one temporary file of this process (under $TMPDIR), rewritten for every input.
//
// The first input byte chooses: bit 0 set, the checksums of the rest (pages, sections, header)
// are recomputed before the check, so that mutations reach the structural checks, the page
// decoding and the totals behind them instead of a checksum mismatch; bit 1 set, every bad page
// is listed (--all).
//
// Beyond the contract (fuzz_contract.hpp): verify_store never throws; every problem's message is
// printable and names the file; a store it passes must open and load every page through the
// reader (that is what "the store verifies" promises).
#include <fcntl.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <vector>

#include "methods/ebp_octree/store/crc32c.hpp"
#include "methods/ebp_octree/store/format.hpp"
#include "methods/ebp_octree/store/reader.hpp"
#include "methods/ebp_octree/store/verify.hpp"
#include "fuzz_contract.hpp"

using namespace bvhbench;

namespace {

bool inside(const std::vector<std::uint8_t>& b, std::uint64_t offset, std::uint64_t size) {
  return offset <= b.size() && size <= b.size() - offset;
}

/// Recomputes the CRC-32C of every page the directory points at, of the sections that have one
/// and of the header, as far as the header and the directory say where they are.
void repair_checksums(std::vector<std::uint8_t>& b) {
  if (b.size() < sizeof(ebp::FileHeader)) return;
  ebp::FileHeader h;
  std::memcpy(&h, b.data(), sizeof h);
  if (inside(b, h.directory.offset, h.directory.size))
    for (std::uint64_t at = h.directory.offset; at + sizeof(ebp::PageEntry) <= h.directory.offset + h.directory.size;
         at += sizeof(ebp::PageEntry)) {
      ebp::PageEntry e;
      std::memcpy(&e, b.data() + at, sizeof e);
      if (!inside(b, e.offset, e.size)) continue;
      e.crc = ebp::crc32c(b.data() + e.offset, e.size);
      std::memcpy(b.data() + at, &e, sizeof e);
    }
  for (ebp::Section* s : {&h.top_nodes, &h.top_children, &h.top_planes, &h.info, &h.directory})
    if (inside(b, s->offset, s->size)) s->crc = ebp::crc32c(b.data() + s->offset, std::size_t(s->size));
  h.header_crc = 0;
  h.header_crc = ebp::crc32c(&h, sizeof h);
  std::memcpy(b.data(), &h, sizeof h);
}

/// This process's temporary store, removed at exit.
const std::string& store_path() {
  static const std::string path = [] {
    std::string p = (std::filesystem::temp_directory_path() / "fuzz_ebp_verify_XXXXXX.ebp").string();
    const int fd = ::mkstemps(p.data(), 4);
    if (fd < 0) fuzz::violated("cannot make a temporary file " + p);
    ::close(fd);
    static const std::string removed_at_exit = p;
    std::atexit([] { std::remove(removed_at_exit.c_str()); });
    return p;
  }();
  return path;
}

void write_file(const std::string& path, const std::vector<std::uint8_t>& b) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
  bool ok = fd >= 0;
  for (std::size_t at = 0; ok && at < b.size();) {
    const ssize_t w = ::write(fd, b.data() + at, b.size() - at);
    ok = w > 0;
    at += ok ? std::size_t(w) : 0;
  }
  if (fd >= 0) ::close(fd);
  if (!ok) fuzz::violated("cannot write " + path);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  std::vector<std::uint8_t> store(data + 1, data + size);
  if (data[0] & 1) repair_checksums(store);
  const std::string& path = store_path();
  write_file(path, store);
  ebp::VerifyOptions opt;
  opt.all = (data[0] & 2) != 0;
  const ebp::VerifyReport rep = ebp::verify_store(path, opt);
  fuzz::check(rep.pages_checked <= rep.pages, "more pages checked than the directory holds");
  for (const ebp::VerifyProblem& p : rep.problems) {
    fuzz::check_message(p.message, path);
    fuzz::check(printable(p.problem) == p.problem, "problem is not printable: " + p.problem);
  }
  if (!opt.all) fuzz::check(rep.problems.size() <= 1, "more than one problem without --all");
  if (rep.ok()) {
    const std::string name = "verified.ebp";
    const bool loads = fuzz::accepts(name, [&] {
      ebp::StoreReader r(store, name, ebp::StoreReader::Options{});
      for (std::uint32_t id = 0; id < r.directory().size(); ++id) (void)r.load_page(id);
    });
    fuzz::check(loads, "the store verifies, but the reader refuses it");
  }
  return 0;
}
