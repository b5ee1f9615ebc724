// CommandModel: parameters.json → an external program (fork, execv) → features.json;
// see command_model.hpp.
#include "calibration/command_model.hpp"
#include "fem/temporary_folder.hpp"

#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <signal.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <utility>

namespace rsw::calibration {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();

std::string read_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// "; its stderr ends: <the last lines, joined by ' | '>", or "; it wrote nothing to
// stderr".
std::string stderr_tail(const fs::path& folder) {
  constexpr std::size_t max_lines = 5, max_chars = 600;
  std::string text = read_text(folder / "stderr.txt");
  if (text.size() > 4 * max_chars) text = text.substr(text.size() - 4 * max_chars);
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    const auto last = line.find_last_not_of(" \t\r");
    if (last != std::string::npos) lines.push_back(line.substr(0, last + 1));
  }
  if (lines.empty()) return "; it wrote nothing to stderr";
  std::string tail;
  const std::size_t first = lines.size() > max_lines ? lines.size() - max_lines : 0;
  for (std::size_t k = first; k < lines.size(); ++k) tail += (tail.empty() ? "" : " | ") + lines[k];
  if (tail.size() > max_chars) tail = "..." + tail.substr(tail.size() - max_chars);
  return "; its stderr ends: " + tail;
}

// Runs the program in `folder`; "" when it exited with code 0, else why not.
std::string run_program(const std::vector<std::string>& arguments, const fs::path& folder) {
  // Everything the child needs is prepared here: between fork and exec only
  // async-signal-safe calls (the caller may have other threads).
  std::vector<char*> argv;
  for (const auto& argument : arguments) argv.push_back(const_cast<char*>(argument.c_str()));
  argv.push_back(nullptr);
  const std::string directory = folder.string();
  const std::string stdout_file = (folder / "stdout.txt").string();
  const std::string stderr_file = (folder / "stderr.txt").string();
  long max_fd = ::sysconf(_SC_OPEN_MAX);
  if (max_fd < 0 || max_fd > 65536) max_fd = 65536;

  // The child reports a failure before exec (stage, errno) through this pipe; exec
  // closes it, so a read of zero bytes means the program started.
  int report[2];
  if (::pipe2(report, O_CLOEXEC) != 0) return std::string("cannot create a pipe: ") + std::strerror(errno);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int error = errno;
    ::close(report[0]);
    ::close(report[1]);
    return std::string("cannot start the command: fork failed: ") + std::strerror(error);
  }
  if (pid == 0) {
    int report_fd = report[1];
    const auto fail = [&report_fd](int stage) {
      const int message[2] = {stage, errno};
      [[maybe_unused]] const ssize_t n = ::write(report_fd, message, sizeof message);
      ::_exit(127);
    };
#ifdef __linux__
    // Die with the process that started it (a farm worker killed at the time limit).
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);
#endif
    // Default signal dispositions and no blocked signals (a farm worker ignores SIGINT
    // and SIGPIPE; ignored signals would stay ignored across exec).
    sigset_t none;
    ::sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    for (const int signal_number : {SIGINT, SIGTERM, SIGPIPE, SIGQUIT, SIGHUP, SIGCHLD}) ::signal(signal_number, SIG_DFL);
    if (::chdir(directory.c_str()) != 0) fail(1);
    const int in = ::open("/dev/null", O_RDONLY);
    if (in < 0 || ::dup2(in, 0) < 0) fail(2);
    const int out = ::open(stdout_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (out < 0 || ::dup2(out, 1) < 0) fail(3);
    const int err = ::open(stderr_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (err < 0 || ::dup2(err, 2) < 0) fail(3);
    // Keep 0-2 and the report pipe (moved to 3); close every other inherited descriptor
    // (a study's HDF5 file, the farm's sockets).
    if (report_fd != 3) {
      if (::dup3(report_fd, 3, O_CLOEXEC) < 0) fail(4);
      report_fd = 3;
    }
#ifdef SYS_close_range
    if (::syscall(SYS_close_range, 4u, ~0u, 0u) != 0)
#endif
      for (long fd = 4; fd < max_fd; ++fd) ::close(static_cast<int>(fd));
    ::execv(argv[0], argv.data());
    fail(5);
  }
  ::close(report[1]);
  int message[2] = {0, 0};
  ssize_t n = 0;
  do {
    n = ::read(report[0], message, sizeof message);
  } while (n < 0 && errno == EINTR);
  ::close(report[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return std::string("cannot wait for the command: ") + std::strerror(errno);
  }
  if (n == static_cast<ssize_t>(sizeof message)) {
    const char* stage = message[0] == 1   ? "cannot enter the run folder"
                        : message[0] == 2 ? "cannot open /dev/null"
                        : message[0] == 3 ? "cannot create stdout.txt or stderr.txt in the run folder"
                        : message[0] == 4 ? "cannot set up its file descriptors"
                                          : "cannot execute it";
    return "cannot run '" + arguments[0] + "': " + stage + " (" + std::strerror(message[1]) + ")";
  }
  if (WIFSIGNALED(status)) {
    const int signal_number = WTERMSIG(status);
    const char* name = ::strsignal(signal_number);
    return "the command was ended by signal " + std::to_string(signal_number) + " (" + (name ? name : "?") + ")" +
           stderr_tail(folder);
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) != 0) {
    return "the command exited with code " + std::to_string(WEXITSTATUS(status)) + stderr_tail(folder);
  }
  return "";
}

// Python's json module writes NaN, Infinity and -Infinity as bare words, which JSON
// does not have: outside strings, NaN becomes null and ±Infinity the strings
// "Infinity", "-Infinity" (read back as ±∞).
std::string accept_python_words(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      out += c;
      if (c == '\\' && i + 1 < text.size()) {
        out += text[++i];
      } else if (c == '"') {
        in_string = false;
      }
      continue;
    }
    if (c == '"') {
      in_string = true;
      out += c;
    } else if (text.compare(i, 3, "NaN") == 0) {
      out += "null";
      i += 2;
    } else if (text.compare(i, 9, "-Infinity") == 0) {
      out += "\"-Infinity\"";
      i += 8;
    } else if (text.compare(i, 8, "Infinity") == 0) {
      out += "\"Infinity\"";
      i += 7;
    } else {
      out += c;
    }
  }
  return out;
}

// The study's features from <folder>/features.json; a failure reason in `failure`.
Eigen::VectorXd read_features(const fs::path& folder, const std::vector<std::string>& names, std::string& failure) {
  Eigen::VectorXd values = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(names.size()), not_a_number);
  const fs::path file = folder / "features.json";
  if (!fs::is_regular_file(file)) {
    failure = "the command exited with code 0 but wrote no features.json" + stderr_tail(folder);
    return values;
  }
  Json root;
  try {
    root = Json::parse(accept_python_words(read_text(file)));
  } catch (const Json::parse_error& e) {
    std::string what = e.what();
    if (const auto bracket = what.find("] "); what.rfind("[json.exception", 0) == 0 && bracket != std::string::npos)
      what = what.substr(bracket + 2);
    failure = "features.json is not valid JSON (" + what + ")";
    return values;
  }
  if (!root.is_object()) {
    failure = std::string("features.json holds ") + root.type_name() + ", not an object {\"feature\": value, ...}";
    return values;
  }
  for (std::size_t k = 0; k < names.size(); ++k) {
    const auto found = root.find(names[k]);
    if (found == root.end() || found->is_null()) continue;  // undefined for this run
    double& value = values[static_cast<Eigen::Index>(k)];
    if (found->is_number()) {
      value = found->get<double>();
    } else if (found->is_string() && (*found == "Infinity" || *found == "-Infinity")) {
      value = *found == "Infinity" ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
    } else {
      failure = "features.json: feature '" + names[k] + "' is " + found->dump() +
                "; allowed: a number, or null or NaN for a feature this run leaves undefined";
      return values;
    }
  }
  return values;
}

}  // namespace

std::vector<std::string> split_command_line(const std::string& text) {
  std::vector<std::string> words;
  std::string word;
  bool in_word = false;
  const auto fail = [&text](const std::string& why) {
    throw std::invalid_argument("'" + text + "': " + why);
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == ' ' || c == '\t') {
      if (in_word) words.push_back(word);
      word.clear();
      in_word = false;
      continue;
    }
    if (c == '\'' || c == '"') {
      const std::size_t close = text.find(c, i + 1);
      if (c == '\'') {
        if (close == std::string::npos) fail("the quote ' at character " + std::to_string(i + 1) + " is not closed");
        word += text.substr(i + 1, close - i - 1);
        i = close;
      } else {
        std::size_t j = i + 1;
        for (; j < text.size() && text[j] != '"'; ++j) {
          if (text[j] == '\\' && j + 1 < text.size() && (text[j + 1] == '"' || text[j + 1] == '\\')) ++j;
          word += text[j];
        }
        if (j >= text.size()) fail("the quote \" at character " + std::to_string(i + 1) + " is not closed");
        i = j;
      }
      in_word = true;
      continue;
    }
    const bool starts_word = !in_word;
    if (std::string("|&;<>()$`\\*?").find(c) != std::string::npos || (starts_word && (c == '~' || c == '#'))) {
      fail(std::string("'") + c + "' at character " + std::to_string(i + 1) +
           " would mean something to a shell, but the command runs without one (no pipes, redirections, "
           "variables or patterns); quote it ('...') to pass it literally, or write a script");
    }
    word += c;
    in_word = true;
  }
  if (in_word) words.push_back(word);
  if (words.empty()) fail("no program; allowed: the program and its arguments, e.g. 'python3 model.py'");
  return words;
}

CommandModel::CommandModel(std::vector<std::string> arguments, std::vector<std::string> parameter_names,
                           std::vector<std::string> feature_names, fs::path run_folder_parent)
    : arguments_(std::move(arguments)), parameter_names_(std::move(parameter_names)),
      feature_names_(std::move(feature_names)), run_folder_parent_(std::move(run_folder_parent)) {
  if (arguments_.empty()) throw std::invalid_argument("CommandModel: no program");
  if (!fs::path(arguments_[0]).is_absolute())
    throw std::invalid_argument("CommandModel: the program '" + arguments_[0] + "' is not an absolute path");
}

EvaluationResult CommandModel::evaluate(const Eigen::VectorXd& theta) const {
  if (static_cast<std::size_t>(theta.size()) != parameter_names_.size()) {
    return EvaluationResult::failure("the command model takes " + std::to_string(parameter_names_.size()) +
                                     " parameters, got " + std::to_string(theta.size()));
  }
  fs::path folder;
  const auto remove_folder = [&folder]() {
    std::error_code ignored;
    if (!folder.empty()) fs::remove_all(folder, ignored);
  };
  try {
    if (run_folder_parent_.empty()) {
      folder = fem::make_temporary_folder("rsw-command-");
    } else {
      std::string pattern = (run_folder_parent_ / "rsw-command-XXXXXX").string();
      if (::mkdtemp(pattern.data()) == nullptr) {
        return EvaluationResult::failure("cannot create a run folder in " + run_folder_parent_.string() + " (" +
                                         std::strerror(errno) + ")");
      }
      folder = pattern;
    }
    Json parameters = Json::object();
    for (std::size_t i = 0; i < parameter_names_.size(); ++i) parameters[parameter_names_[i]] = theta[static_cast<Eigen::Index>(i)];
    {
      std::ofstream out(folder / "parameters.json", std::ios::binary);
      out << parameters.dump(1) << "\n";
      if (!out) {
        remove_folder();
        return EvaluationResult::failure("cannot write parameters.json in " + folder.string());
      }
    }
    std::string failure = run_program(arguments_, folder);
    Eigen::VectorXd values;
    if (failure.empty()) values = read_features(folder, feature_names_, failure);
    remove_folder();
    if (!failure.empty()) return EvaluationResult::failure(failure);
    return EvaluationResult::success(values);
  } catch (const std::exception& e) {
    remove_folder();
    return EvaluationResult::failure(std::string("command model: ") + e.what());
  }
}

}  // namespace rsw::calibration
