// Wall time per named part of a run (s), for the timing table of summary.json.
//
// start(part) ends the running part and starts `part`; the time of each part is
// summed over all its intervals, in the order the parts first ran.
#pragma once

#include <algorithm>
#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace rsw::physics {

class Stopwatch {
 public:
  explicit Stopwatch(std::vector<std::pair<std::string, double>>& timing) : timing_(timing) {}
  void start(const std::string& part) {
    stop();
    part_ = part;
    t0_ = std::chrono::steady_clock::now();
  }
  void stop() {
    if (part_.empty()) return;
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    auto it = std::find_if(timing_.begin(), timing_.end(), [&](const auto& p) { return p.first == part_; });
    if (it == timing_.end()) timing_.emplace_back(part_, dt);
    else it->second += dt;
    part_.clear();
  }

 private:
  std::vector<std::pair<std::string, double>>& timing_;
  std::string part_;
  std::chrono::steady_clock::time_point t0_;
};

}  // namespace rsw::physics
