#pragma once
/// The whole-store check of a `.ebp` (`bvhbench ebp verify`, OUT_OF_CORE.md "Verifying a store").
///
/// Queries check a page only when they read it, so a store copied to another machine could be
/// corrupt anywhere and nothing would say so until a query reached the bad page. verify_store()
/// opens the store with StoreReader (header, its CRC-32C, every section's CRC-32C, the top tree,
/// the directory) and then loads every page with StoreReader::load_page, the very function the
/// page cache calls: CRC-32C, every structural check, the decode. "The store verifies" therefore
/// means "every page would load". On top of that it checks what only a whole pass can: the
/// directory's per-page counts and the header's totals (which `ebp info` and the method report)
/// agree with the pages.
///
/// Memory: the reader's pinned part (header, top tree, directory: about 1 % of the file) and one
/// decoded page per thread at a time; the file is read with pread, page by page, never whole.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace ebp {

/// One thing wrong with a store.
struct VerifyProblem {
  /// The bad page's id; -1 when the problem is in the header, a section, the top tree or the
  /// directory (the message names which), or in counts that span the whole store.
  std::int64_t page = -1;
  std::uint64_t offset = 0, size = 0;  ///< bytes: the page's place in the file (page >= 0 only)
  std::string problem;                 ///< what is wrong, e.g. "checksum mismatch (corrupted)" (printable)
  std::string message;                 ///< "FILE: page 17 (bytes 69632..86016): problem" (printable)
};

struct VerifyOptions {
  /// false: stop at the first bad page. true: go on and list every bad page. A bad header,
  /// section, top tree or directory always ends the check there: without them nothing says where
  /// the pages are.
  bool all = false;
  int threads = 1;  ///< pages decoded in parallel (TBB, at most the cores); problems still in page order
  /// Called from the calling thread after each batch of pages: bytes of pages checked so far, of all.
  std::function<void(std::uint64_t done, std::uint64_t total)> progress;
};

struct VerifyReport {
  std::string path;
  std::uint64_t file_bytes = 0;     ///< the file's size on disk
  std::uint64_t pages = 0;          ///< in the directory (0 if the store did not open)
  std::uint64_t pages_checked = 0;  ///< loaded (good or bad) before the check ended
  std::uint64_t bytes_read = 0;     ///< header + sections + pages read and checksummed
  double seconds = 0;               ///< wall time of the whole check, the open included
  std::vector<VerifyProblem> problems;  ///< the store's problems, bad pages in id (= file) order
  bool ok() const { return problems.empty(); }
};

/// Checks the store at `path` (see above). Never throws for a bad or unreadable store: every
/// problem the reader would raise as a bvhbench::InputError is in the report instead.
VerifyReport verify_store(const std::string& path, const VerifyOptions& opt = {});

}  // namespace ebp
