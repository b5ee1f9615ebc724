// CommandModel (calibration/command_model.hpp) without the farm: the words of a command
// line, and the file protocol against small POSIX sh scripts written by the tests —
// parameters.json as written, features.json as read (NaN, null, missing, Infinity),
// and every kind of failed run with its reason.
#include "calibration/command_model.hpp"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
namespace cal = rsw::calibration;

namespace {

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("rsw_command_model_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// An executable /bin/sh script with `body`.
fs::path write_script(const fs::path& dir, const std::string& name, const std::string& body) {
  const fs::path path = dir / name;
  std::ofstream(path) << "#!/bin/sh\n" << body;
  ::chmod(path.c_str(), 0755);
  return path;
}

cal::CommandModel model_of(const fs::path& script, const fs::path& runs, std::vector<std::string> features = {"y", "z"}) {
  return cal::CommandModel({script.string()}, {"a", "b"}, std::move(features), runs);
}

Eigen::VectorXd point(double a, double b) {
  Eigen::VectorXd theta(2);
  theta << a, b;
  return theta;
}

}  // namespace

TEST(CommandLine, SplitsIntoWordsWithoutAShell) {
  using Words = std::vector<std::string>;
  EXPECT_EQ(cal::split_command_line("python3  model.py\t--x 1"), (Words{"python3", "model.py", "--x", "1"}));
  EXPECT_EQ(cal::split_command_line("run 'a b' \"c \\\"d\\\" \\\\\" e'f'g"),
            (Words{"run", "a b", "c \"d\" \\", "efg"}));
  EXPECT_EQ(cal::split_command_line("run '' 'x|y' \"$HOME\" a~b a#b"), (Words{"run", "", "x|y", "$HOME", "a~b", "a#b"}));
  for (const char* bad : {"", "   ", "a | b", "a > out", "a; b", "a && b", "echo $HOME", "ls *.py", "a 'b", "a \"b",
                          "cd ~", "a #comment", "a `b`", "a (b)", "a\\ b"}) {
    EXPECT_THROW(cal::split_command_line(bad), std::invalid_argument) << bad;
  }
  try {
    cal::split_command_line("model > out.txt");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "'model > out.txt': '>' at character 7 would mean something to a shell, but the command runs without "
              "one (no pipes, redirections, variables or patterns); quote it ('...') to pass it literally, or write "
              "a script");
  }
}

TEST(CommandModel, WritesTheParametersAndReadsTheFeaturesInAFreshFolderItRemoves) {
  const fs::path dir = fresh_dir("protocol");
  const fs::path runs = dir / "runs";
  fs::create_directories(runs);
  // Keeps a copy of parameters.json and the folder it ran in; Python-style bare words,
  // a null, a missing and an extra feature.
  const fs::path script = write_script(dir, "model.sh", "cp parameters.json " + (dir / "seen.json").string() +
                                                            "\npwd > " + (dir / "folder.txt").string() +
                                                            "\necho '{\"y\": NaN, \"extra\": 1, \"w\": -Infinity}' "
                                                            "> features.json\n");
  const cal::CommandModel model = cal::CommandModel({script.string()}, {"a", "b"}, {"y", "z", "w"}, runs);
  // Values whose decimal text needs all 17 digits, and a tiny one.
  const double a = 0.1 + 0.2, b = 1e-300 / 3;
  const cal::EvaluationResult result = model.evaluate(point(a, b));
  ASSERT_TRUE(result.ok()) << result.failure_reason();
  EXPECT_TRUE(std::isnan(result.features()[0]));  // NaN: undefined
  EXPECT_TRUE(std::isnan(result.features()[1]));  // missing: undefined
  EXPECT_EQ(result.features()[2], -INFINITY);     // the farm records it as a failed run
  const auto seen = nlohmann::json::parse(read_file(dir / "seen.json"));
  EXPECT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen["a"].get<double>(), a);  // bit for bit
  EXPECT_EQ(seen["b"].get<double>(), b);
  std::string folder = read_file(dir / "folder.txt");
  folder.pop_back();
  EXPECT_EQ(fs::path(folder).parent_path(), runs);
  EXPECT_EQ(fs::path(folder).filename().string().rfind("rsw-command-", 0), 0u) << folder;
  EXPECT_FALSE(fs::exists(folder));
  EXPECT_TRUE(fs::is_empty(runs));
  fs::remove_all(dir);
}

TEST(CommandModel, FailedRunsCarryTheirReasons) {
  const fs::path dir = fresh_dir("failures");
  const auto reason = [&dir](const std::string& body) {
    const cal::EvaluationResult result = model_of(write_script(dir, "model.sh", body), dir).evaluate(point(1, 2));
    EXPECT_FALSE(result.ok()) << body;
    return result.ok() ? std::string() : result.failure_reason();
  };
  EXPECT_EQ(reason("for k in 1 2 3 4 5 6 7; do echo \"line $k\" >&2; done\nexit 3\n"),
            "the command exited with code 3; its stderr ends: line 3 | line 4 | line 5 | line 6 | line 7");
  EXPECT_EQ(reason("exit 1\n"), "the command exited with code 1; it wrote nothing to stderr");
  EXPECT_EQ(reason("echo 'no features' >&2\n"),
            "the command exited with code 0 but wrote no features.json; its stderr ends: no features");
  EXPECT_EQ(reason("kill -9 $$\n"), "the command was ended by signal 9 (Killed); it wrote nothing to stderr");
  EXPECT_EQ(reason("echo '[1, 2]' > features.json\n"),
            "features.json holds array, not an object {\"feature\": value, ...}");
  EXPECT_EQ(reason("echo '{\"y\": \"high\"}' > features.json\n"),
            "features.json: feature 'y' is \"high\"; allowed: a number, or null or NaN for a feature this run "
            "leaves undefined");
  EXPECT_EQ(reason("echo '{\"y\": 1,' > features.json\n").rfind("features.json is not valid JSON (parse error", 0), 0u);
  // A file that cannot be executed.
  const fs::path plain = dir / "plain.txt";
  std::ofstream(plain) << "not a program\n";
  const cal::EvaluationResult result = model_of(plain, dir).evaluate(point(1, 2));
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.failure_reason(), "cannot run '" + plain.string() + "': cannot execute it (Permission denied)");
  // No run folders are left behind.
  for (const auto& entry : fs::directory_iterator(dir))
    EXPECT_NE(entry.path().filename().string().rfind("rsw-command-", 0), 0u) << entry.path();
  fs::remove_all(dir);
}

TEST(CommandModel, RunsFromSeveralThreadsAtOnce) {
  const fs::path dir = fresh_dir("threads");
  // y = a + b, z = a·b by the shell's integer arithmetic.
  const fs::path script = write_script(
      dir, "model.sh",
      "a=$(sed -n 's/.*\"a\": *\\([0-9-]*\\).*/\\1/p' parameters.json)\n"
      "b=$(sed -n 's/.*\"b\": *\\([0-9-]*\\).*/\\1/p' parameters.json)\n"
      "echo \"{\\\"y\\\": $((a + b)), \\\"z\\\": $((a * b))}\" > features.json\n");
  const cal::CommandModel model = model_of(script, dir);
  std::vector<cal::EvaluationResult> results(8, cal::EvaluationResult::failure("not run"));
  std::vector<std::thread> threads;
  for (int k = 0; k < 8; ++k) {
    threads.emplace_back([&model, &results, k]() { results[static_cast<std::size_t>(k)] = model.evaluate(point(k, 3)); });
  }
  for (auto& thread : threads) thread.join();
  for (int k = 0; k < 8; ++k) {
    const cal::EvaluationResult& result = results[static_cast<std::size_t>(k)];
    ASSERT_TRUE(result.ok()) << k << ": " << result.failure_reason();
    EXPECT_EQ(result.features()[0], k + 3);
    EXPECT_EQ(result.features()[1], 3 * k);
  }
  fs::remove_all(dir);
}

TEST(CommandModel, NeedsAnAbsoluteProgram) {
  EXPECT_THROW(cal::CommandModel({}, {"a"}, {"y"}, "/tmp"), std::invalid_argument);
  EXPECT_THROW(cal::CommandModel({"model.py"}, {"a"}, {"y"}, "/tmp"), std::invalid_argument);
}
