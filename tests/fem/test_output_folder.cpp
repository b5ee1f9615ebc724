// fem::OutputFolder: which folders a run may write into, the marker's list of what it
// wrote, that nothing else is ever removed or replaced, and the lock that refuses a
// second run into the same folder at once.
#include "fem/output_folder.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using rsw::fem::OutputFolder;
using rsw::fem::OutputFolderError;
using rsw::fem::OutputFolderOptions;

namespace {

fs::path fresh(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("rsw_output_folder_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

void write(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
}

std::string read(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

OutputFolderOptions simulate(bool overwrite = false) {
  OutputFolderOptions o;
  o.kind = "simulate";
  o.overwrite = overwrite;
  return o;
}

// The message of the OutputFolderError that `f` throws ("" if none).
template <class F>
std::string refusal(F f) {
  try {
    f();
  } catch (const OutputFolderError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(OutputFolder, CreatesANewFolderWithItsMarker) {
  const fs::path dir = fresh("new") / "a" / "b";
  {
    OutputFolder folder(dir, simulate());
    EXPECT_TRUE(fs::is_directory(dir));
    EXPECT_TRUE(fs::exists(dir / OutputFolder::marker_name));
  }
  fs::remove_all(dir.parent_path().parent_path());
}

TEST(OutputFolder, AcceptsAnEmptyFolderAndAFolderItMadeBefore) {
  const fs::path dir = fresh("empty");
  fs::create_directories(dir);
  {
    OutputFolder folder(dir, simulate());
    folder.record("results.h5");
    write(dir / "results.h5", "one");
  }
  OutputFolder again(dir, simulate());
  EXPECT_TRUE(again.wrote("results.h5"));
  fs::remove_all(dir);
}

TEST(OutputFolder, RefusesANonEmptyFolderItDidNotMake) {
  const fs::path dir = fresh("foreign");
  fs::create_directories(dir);
  write(dir / "weld.yaml", "case");
  const std::string message = refusal([&] { OutputFolder folder(dir, simulate()); });
  EXPECT_NE(message.find(dir.string()), std::string::npos) << message;
  EXPECT_NE(message.find("weld.yaml"), std::string::npos) << message;
  EXPECT_NE(message.find("--overwrite"), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(dir / OutputFolder::marker_name));
  EXPECT_EQ(read(dir / "weld.yaml"), "case");
  fs::remove_all(dir);
}

TEST(OutputFolder, RefusesAFileEvenWithOverwrite) {
  const fs::path base = fresh("file");
  fs::create_directories(base);
  const fs::path file = base / "notes.txt";
  write(file, "mine");
  for (const bool overwrite : {false, true}) {
    const std::string message = refusal([&] { OutputFolder folder(file, simulate(overwrite)); });
    EXPECT_NE(message.find("is a file, not a folder"), std::string::npos) << message;
    EXPECT_TRUE(fs::is_regular_file(file));
    EXPECT_EQ(read(file), "mine");
  }
  fs::remove_all(base);
}

TEST(OutputFolder, OverwriteAddsToAFolderButNeverRemovesOrReplacesWhatItDidNotWrite) {
  const fs::path dir = fresh("overwrite");
  fs::create_directories(dir);
  write(dir / "weld.yaml", "case");
  write(dir / "summary.json", "the user's");
  OutputFolder folder(dir, simulate(true));
  EXPECT_TRUE(fs::exists(dir / OutputFolder::marker_name));
  const std::string message = refusal([&] { folder.clear({"results.h5", "summary.json"}); });
  EXPECT_NE(message.find((dir / "summary.json").string()), std::string::npos) << message;
  EXPECT_EQ(read(dir / "summary.json"), "the user's");
  folder.clear({"results.h5", "fields_*"});  // nothing of those here: nothing to do
  EXPECT_EQ(read(dir / "weld.yaml"), "case");
  fs::remove_all(dir);
}

TEST(OutputFolder, ClearRemovesOnlyTheEntriesTheMarkerLists) {
  const fs::path dir = fresh("clear");
  OutputFolder folder(dir, simulate());
  for (const char* name : {"results.h5", "fields_0001.vtm", "fields_0001"}) folder.record(name);
  write(dir / "results.h5", "old");
  write(dir / "fields_0001.vtm", "old");
  fs::create_directories(dir / "fields_0001");
  write(dir / "fields_0001" / "sheet_1.vtu", "old");
  write(dir / "keep.txt", "mine");
  folder.clear({"results.h5", "fields_*", "signals.csv"});
  EXPECT_FALSE(fs::exists(dir / "results.h5"));
  EXPECT_FALSE(fs::exists(dir / "fields_0001.vtm"));
  EXPECT_FALSE(fs::exists(dir / "fields_0001"));
  EXPECT_EQ(read(dir / "keep.txt"), "mine");
  write(dir / "fields_user.txt", "mine");  // begins like an output: refused, and nothing removed
  folder.record("results.h5");
  write(dir / "results.h5", "new");
  EXPECT_FALSE(refusal([&] { folder.clear({"results.h5", "fields_*"}); }).empty());
  EXPECT_EQ(read(dir / "results.h5"), "new");
  EXPECT_EQ(read(dir / "fields_user.txt"), "mine");
  fs::remove_all(dir);
}

TEST(OutputFolder, InstallMovesStagedFilesIntoPlaceAndListsThem) {
  const fs::path dir = fresh("install");
  OutputFolder folder(dir, simulate());
  folder.record("summary.json");
  write(dir / "summary.json", "old");
  folder.record("partial");
  fs::create_directories(dir / "partial" / "fields_0000");
  write(dir / "partial" / "summary.json", "new");
  write(dir / "partial" / "fields_0000" / "a.vtu", "new");
  folder.install(dir / "partial");
  EXPECT_EQ(read(dir / "summary.json"), "new");
  EXPECT_EQ(read(dir / "fields_0000" / "a.vtu"), "new");
  EXPECT_FALSE(fs::exists(dir / "partial"));
  EXPECT_TRUE(folder.wrote("fields_0000"));
  fs::remove_all(dir);
}

TEST(OutputFolder, InstallRefusesToReplaceAFileItDidNotWrite) {
  const fs::path dir = fresh("install_foreign");
  OutputFolder folder(dir, simulate());
  folder.record("partial");
  fs::create_directories(dir / "partial");
  write(dir / "partial" / "signals.csv", "new");
  write(dir / "signals.csv", "the user's, made during the run");
  EXPECT_FALSE(refusal([&] { folder.install(dir / "partial"); }).empty());
  EXPECT_EQ(read(dir / "signals.csv"), "the user's, made during the run");
  fs::remove_all(dir);
}

TEST(OutputFolder, ASecondRunIntoAFolderInUseIsRefusedAtOnce) {
  const fs::path dir = fresh("lock");
  {
    OutputFolder first(dir, simulate());
    const std::string message = refusal([&] { OutputFolder second(dir, simulate()); });
    EXPECT_NE(message.find("in use by another rsw run"), std::string::npos) << message;
    OutputFolderOptions shared = simulate();
    shared.shared = true;
    EXPECT_FALSE(refusal([&] { OutputFolder reader(dir, shared); }).empty());
  }
  OutputFolder after(dir, simulate());  // released with the first claim
  fs::remove_all(dir);
}

TEST(OutputFolder, SharedClaimsCoexistAndExcludeAnExclusiveOne) {
  const fs::path dir = fresh("shared");
  OutputFolderOptions shared;
  shared.kind = "study";
  shared.shared = true;
  OutputFolder a(dir, shared);
  OutputFolder b(dir, shared);
  a.record("one.h5");
  b.record("two.h5");
  EXPECT_FALSE(refusal([&] { OutputFolder c(dir, simulate()); }).empty());
  OutputFolder d(dir, shared);
  EXPECT_TRUE(d.wrote("one.h5"));
  EXPECT_TRUE(d.wrote("two.h5"));
  fs::remove_all(dir);
}

TEST(OutputFolder, AdoptsAnUnmarkedFolderHoldingItsOwnEvidence) {
  const fs::path dir = fresh("adopt");
  fs::create_directories(dir);
  write(dir / "table1.h5", "an earlier version's results");
  write(dir / "notes.txt", "mine");
  OutputFolderOptions o;
  o.kind = "study";
  o.evidence = {"table1.h5", "table1_runs.csv"};
  {
    OutputFolder folder(dir, o);
    EXPECT_TRUE(folder.wrote("table1.h5"));
    EXPECT_FALSE(folder.wrote("notes.txt"));
  }
  fs::remove(dir / OutputFolder::marker_name);
  o.evidence = {"other.h5"};
  EXPECT_FALSE(refusal([&] { OutputFolder folder(dir, o); }).empty());
  fs::remove_all(dir);
}
