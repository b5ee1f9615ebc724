// Claiming an output folder: the checks, the lock and the marker's list of written
// entries; see output_folder.hpp.
#include "fem/output_folder.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <system_error>

namespace rsw::fem {

namespace fs = std::filesystem;

namespace {

const char* const marker_header =
    "# rsw output folder. rsw writes into a folder only if it is new, empty or holds this file,\n"
    "# and replaces or removes only the entries listed below, which it wrote (kind, tab, name).\n";

bool exists_here(const fs::path& path) {
  std::error_code ec;
  return fs::symlink_status(path, ec).type() != fs::file_type::not_found && !ec;
}

// Appends `text` with one write (O_APPEND: lines of concurrent writers do not mix).
void append_text(const fs::path& file, const std::string& text) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw OutputFolderError("cannot write '" + file.string() + "': " + std::strerror(errno));
  const ssize_t n = ::write(fd, text.data(), text.size());
  const int error = errno;
  ::close(fd);
  if (n != static_cast<ssize_t>(text.size()))
    throw OutputFolderError("cannot write '" + file.string() + "': " + std::strerror(error));
}

}  // namespace

std::string OutputFolder::refusal(const std::string& why) const {
  std::string shown = "'" + folder_.string() + "'";
  if (folder_.is_relative()) {
    std::error_code ec;
    std::string absolute = fs::absolute(folder_, ec).lexically_normal().string();
    if (absolute.size() > 1 && absolute.back() == '/') absolute.pop_back();  // "/a/." is "/a/"
    if (!ec && absolute != folder_.string()) shown += " (" + absolute + ")";
  }
  return "output folder " + shown + " " + why;
}

OutputFolder::OutputFolder(fs::path folder, OutputFolderOptions options)
    : folder_(std::move(folder)), options_(std::move(options)) {
  if (folder_.empty()) folder_ = ".";
  std::error_code ec;
  const fs::file_status status = fs::status(folder_, ec);
  if (status.type() != fs::file_type::not_found && !fs::is_directory(status)) {
    throw OutputFolderError(refusal("is a file, not a folder; rsw writes its results into a folder and never "
                                    "replaces a file by one (" + options_.option +
                                    " does not either): choose another output folder"));
  }
  fs::create_directories(folder_, ec);
  if (ec) throw OutputFolderError(refusal("cannot be created: " + ec.message()));

  lock_fd_ = ::open(folder_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (lock_fd_ < 0) throw OutputFolderError(refusal(std::string("cannot be opened: ") + std::strerror(errno)));
  if (::flock(lock_fd_, (options_.shared ? LOCK_SH : LOCK_EX) | LOCK_NB) != 0) {
    const int error = errno;
    ::close(lock_fd_);
    lock_fd_ = -1;
    if (error == EWOULDBLOCK)
      throw OutputFolderError(refusal("is in use by another rsw run (it holds the folder's lock); wait until "
                                      "it has finished, or choose another output folder"));
    throw OutputFolderError(refusal(std::string("cannot be locked: ") + std::strerror(error)));
  }

  try {
    check_and_mark();
  } catch (...) {
    ::close(lock_fd_);  // the destructor of an object whose constructor threw does not run
    lock_fd_ = -1;
    throw;
  }
}

void OutputFolder::check_and_mark() {
  const fs::path marker = folder_ / marker_name;
  if (exists_here(marker)) {
    load_marker();
    return;
  }
  std::vector<std::string> present, evidence;
  for (const auto& entry : fs::directory_iterator(folder_)) {
    const std::string name = entry.path().filename().string();
    // A marker that appeared since the check above is another shared claim's (an MPI
    // rank or array task that created it first): rsw's own, not a stranger's file.
    if (name == marker_name) continue;
    present.push_back(name);
    for (const auto& e : options_.evidence)
      if (name == e) evidence.push_back(name);
  }
  if (!present.empty() && evidence.empty() && !options_.overwrite) {
    throw OutputFolderError(refusal(
        "holds entries rsw did not write (e.g. '" + present.front() + "') and no marker " + marker_name +
        "; rsw writes only into a new folder, an empty one or one it made before: choose another output folder, "
        "or add rsw's files to this one with " + options_.option + " (which removes and replaces nothing rsw did "
        "not write)"));
  }
  // A new marker: created once even if several shared claims race for it.
  const int fd = ::open(marker.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd >= 0) {
    const std::string header(marker_header);
    const bool ok = ::write(fd, header.data(), header.size()) == static_cast<ssize_t>(header.size());
    ::close(fd);
    if (!ok) throw OutputFolderError("cannot write '" + marker.string() + "'");
  } else if (errno != EEXIST) {
    throw OutputFolderError("cannot write '" + marker.string() + "': " + std::strerror(errno));
  }
  load_marker();
  for (const auto& name : evidence) record(name);
}

OutputFolder::~OutputFolder() {
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the lock
}

void OutputFolder::load_marker() {
  entries_.clear();
  names_.clear();
  std::ifstream in(folder_ / marker_name);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const auto tab = line.find('\t');
    if (tab == std::string::npos) continue;
    entries_.emplace_back(line.substr(0, tab), line.substr(tab + 1));
    names_.insert(line.substr(tab + 1));
  }
}

bool OutputFolder::wrote(const std::string& name) const { return names_.count(name) > 0; }

void OutputFolder::record(const std::string& name) {
  if (wrote(name)) return;
  append_text(folder_ / marker_name, options_.kind + "\t" + name + "\n");
  entries_.emplace_back(options_.kind, name);
  names_.insert(name);
}

void OutputFolder::check_replaceable(const std::string& name) const {
  if (!exists_here(folder_ / name) || wrote(name)) return;
  throw OutputFolderError("'" + (folder_ / name).string() + "' was not written by rsw (" + marker_name +
                          " does not list it) and rsw would write over it: move it away, or choose another "
                          "output folder");
}

void OutputFolder::check(const std::vector<std::string>& names) {
  load_marker();
  for (const auto& name : names) check_replaceable(name);
}

void OutputFolder::clear(const std::vector<std::string>& names) {
  load_marker();
  std::vector<std::string> existing;
  for (const auto& name : names) {
    if (!name.empty() && name.back() == '*') {
      const std::string prefix = name.substr(0, name.size() - 1);
      for (const auto& entry : fs::directory_iterator(folder_)) {
        const std::string n = entry.path().filename().string();
        if (n.compare(0, prefix.size(), prefix) == 0 && n != marker_name) existing.push_back(n);
      }
    } else if (exists_here(folder_ / name)) {
      existing.push_back(name);
    }
  }
  for (const auto& name : existing) check_replaceable(name);  // refuse before removing anything
  for (const auto& name : existing) fs::remove_all(folder_ / name);
}

void OutputFolder::install(const fs::path& staging, const std::string& last) {
  load_marker();
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(staging)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end(), [&](const std::string& a, const std::string& b) {
    return (a == last) != (b == last) ? b == last : a < b;
  });
  for (const auto& name : names) check_replaceable(name);
  for (const auto& name : names) {
    record(name);
    const fs::path target = folder_ / name;
    // rename() replaces a file at once; an earlier folder of the same name goes first.
    if (fs::is_directory(fs::symlink_status(target))) fs::remove_all(target);
    fs::rename(staging / name, target);
  }
  fs::remove(staging);
}

}  // namespace rsw::fem
