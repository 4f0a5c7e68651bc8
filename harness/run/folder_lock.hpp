#pragma once
/// One writer per results folder: `bvhbench suite` holds OUT/suite.lock while it runs. Two runs
/// on one folder would time each job under the other's load and overwrite each other's results
/// with no warning; the second is refused instead, naming the holder. A lock whose holder is
/// gone (its pid is dead on this host: a killed run) is taken over, with a message.
#include <string>

namespace bvhbench {

class FolderLock {
 public:
  /// Takes `folder`/suite.lock (the folder must exist). Throws InputError "FOLDER/suite.lock: ..."
  /// naming the holder's pid, host and start time when another live run holds it, or when its
  /// holder runs on another host (whose pids this host cannot check). Says on `stderr` when it
  /// takes over a stale lock.
  explicit FolderLock(const std::string& folder);
  /// Removes the lock file, if it is still this process's.
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::string content_;  ///< what this process wrote: removed only while it is still that
};

}  // namespace bvhbench
