// Output folders that are safe to write into: a program claims a folder before it
// writes, and the claim refuses any folder it may not use.
//
// A folder may be used if it is new (created), empty, or holds the marker file
// `.rsw-output`, written by an earlier claim; the marker lists, line by line, the
// entries (files and folders) a program wrote there and which kind of run wrote each
// ("simulate\tresults.h5"). Anything else is refused with OutputFolderError naming
// the path and why: a path that is a file, a non-empty folder without the marker (the
// working directory, the folder of an input file). `overwrite` accepts a non-empty
// folder without the marker and adds the marker; it never makes an entry the marker
// does not list replaceable: nothing a program did not write is ever removed or
// written over (clear() and install() refuse it).
//
// The claim holds a lock on the folder (flock on the folder itself) until it is
// destroyed: exclusive (one run writes the folder) or shared (several runs, e.g. the
// tasks of one study, write distinct files); a conflicting lock is refused at once.
//
// An unmarked folder that holds one of `evidence` (names only a program's own run
// writes, e.g. a study's results file) was made by a version before the marker: it is
// adopted, the marker written and the evidence entries it holds listed.
#pragma once

#include "fem/config.hpp"

#include <filesystem>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace rsw::fem {

// A folder the program may not use, or an entry in it that it did not write. A
// ConfigError: the user's choice of folder is bad input.
class OutputFolderError : public ConfigError {
 public:
  using ConfigError::ConfigError;
};

struct OutputFolderOptions {
  std::string kind;          // what writes: "simulate", "study", ...; recorded per entry
  bool overwrite = false;    // accept a non-empty folder without the marker
  bool shared = false;       // a shared lock (several runs at once); default exclusive
  std::vector<std::string> evidence;  // entry names that show an earlier run made the folder
  std::string option = "--overwrite";  // the option a refusal names
};

class OutputFolder {
 public:
  static constexpr const char* marker_name = ".rsw-output";

  // Creates the folder if absent, locks it and checks it (see above).
  OutputFolder(std::filesystem::path folder, OutputFolderOptions options);
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  const std::filesystem::path& path() const { return folder_; }

  // Whether the marker lists `name` (an entry of the folder), of any kind.
  bool wrote(const std::string& name) const;
  // Refuses (OutputFolderError) if one of `names` exists and the marker does not list it.
  void check(const std::vector<std::string>& names);
  // Lists `name` in the marker as written by this kind (before it is written).
  void record(const std::string& name);
  // Makes room for entries about to be written: `names` are entry names, one ending in
  // '*' stands for every entry beginning with the rest. An existing entry the marker
  // lists is removed (a folder with what is in it); one it does not list is refused.
  void clear(const std::vector<std::string>& names);
  // Moves every entry of `staging` (a folder of this claim's) into the folder, each
  // listed first, `last` (e.g. the file that says a result is complete) after all
  // others, and removes `staging`. An entry of the same name is replaced only if the
  // marker lists it (a folder is removed first; a file is replaced at once by
  // rename); one the marker does not list is refused before anything moves.
  void install(const std::filesystem::path& staging, const std::string& last = "");

 private:
  void check_and_mark();  // the checks after the lock, and a new marker
  void load_marker();
  void write_marker() const;
  // Refuses if `name` exists in the folder and the marker does not list it.
  void check_replaceable(const std::string& name) const;
  std::string refusal(const std::string& why) const;

  std::filesystem::path folder_;
  OutputFolderOptions options_;
  int lock_fd_ = -1;
  std::vector<std::pair<std::string, std::string>> entries_;  // (kind, name), in the marker's order
  std::set<std::string> names_;
};

}  // namespace rsw::fem
