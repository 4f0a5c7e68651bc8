// The results folder's lock (folder_lock.hpp): a file made with O_EXCL, holding who took it.
#include "harness/run/folder_lock.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>

#include <nlohmann/json.hpp>

#include "harness/run/system_info.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/printable.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace bvhbench {
namespace {

std::string this_host() {
  char host[256] = {0};
  gethostname(host, sizeof host - 1);
  return host;
}

std::string read_text(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

/// Creates `path` with `text` unless it exists. False when it exists; throws for other failures.
bool create_exclusive(const std::string& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    if (errno == EEXIST) return false;
    throw InputError(printable(path) + ": cannot create the results folder's lock: " + std::strerror(errno));
  }
  const ssize_t n = ::write(fd, text.data(), text.size());
  ::close(fd);
  if (n != ssize_t(text.size())) throw InputError(printable(path) + ": cannot write the results folder's lock");
  return true;
}

}  // namespace

FolderLock::FolderLock(const std::string& folder) : path_((fs::path(folder) / "suite.lock").string()) {
  const std::string host = this_host();
  content_ = json{{"pid", long(::getpid())}, {"host", host}, {"started", iso8601_now()}}.dump() + "\n";
  // Twice at most: once, and once more after taking over a stale lock.
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (create_exclusive(path_, content_)) return;
    const std::string text = read_text(path_);
    const json holder = json::parse(text, nullptr, false);
    if (!holder.is_object() || !holder.contains("pid") || !holder["pid"].is_number_integer() ||
        !holder.contains("host") || !holder["host"].is_string())
      throw InputError(printable(path_) + ": another bvhbench suite may be writing this results folder (its lock "
                       "file cannot be read: " + printable(text.substr(0, 200)) +
                       "); if none is, remove the lock file and run again");
    const long pid = holder["pid"].get<long>();
    const std::string holder_host = holder["host"].get<std::string>();
    const std::string started = holder.value("started", std::string("an unknown time"));
    const std::string who = "bvhbench suite pid " + std::to_string(pid) + " on host " + printable(holder_host) +
                            ", started " + printable(started);
    const bool dead = holder_host == host && pid > 0 && ::kill(pid_t(pid), 0) != 0 && errno == ESRCH;
    if (!dead)
      throw InputError(printable(path_) + ": this results folder is being written by " + who +
                       " (a results folder has one writer: wait for that run, stop it, or give another --out)" +
                       (holder_host == host ? std::string()
                                            : "; it runs on another host, whose processes cannot be checked from "
                                              "here: if it is gone, remove the lock file"));
    std::cerr << "bvhbench suite: taking over " << printable(path_) << ", left by " << who
              << ", which is no longer running\n";
    fs::remove(path_);
  }
  throw InputError(printable(path_) + ": another bvhbench suite took this results folder's lock at the same time");
}

FolderLock::~FolderLock() {
  std::error_code ec;
  if (read_text(path_) == content_) fs::remove(path_, ec);
}

}  // namespace bvhbench
