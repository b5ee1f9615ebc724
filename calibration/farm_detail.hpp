// Small helpers shared by the evaluation farm's parts (farm.cpp, farm_protocol.cpp,
// worker_pool.cpp, mpi_ranks.cpp, study_results_file.cpp): wall clock, text of numbers
// and lists. Internal to calibration/.
#pragma once

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace rsw::calibration::farm_detail {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

inline constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();

inline double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

inline std::string join(const std::vector<std::string>& parts, const std::string& separator) {
  std::string result;
  for (std::size_t i = 0; i < parts.size(); ++i) result += (i ? separator : "") + parts[i];
  return result;
}

// All 17 significant digits: the value read back is the value written.
inline std::string number_text(double value) {
  std::ostringstream out;
  out << std::setprecision(17) << value;
  return out.str();
}

}  // namespace rsw::calibration::farm_detail
