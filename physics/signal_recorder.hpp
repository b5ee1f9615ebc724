// The weld's signal table: columns registered once as (name, unit, getter), one row
// appended per output time.
//
// A column has a name, a unit and a one-line description (results.h5 carries it).
// A getter reads one value from a snapshot of the run's state (`State`, whatever the
// driver records from: the solvers' outputs at that time, computed once per row), so
// the name, the unit and the value of a column are declared in one place. Values are
// in SI units but for temperatures (°C), as the unit strings say.
#pragma once

#include "physics/weld_simulation.hpp"

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace rsw::physics {

template <class State>
class SignalRecorder {
 public:
  using Getter = std::function<double(const State&)>;

  // Records into `signals` (its names, units and columns are replaced).
  explicit SignalRecorder(Signals& signals) : signals_(signals) { signals_ = Signals{}; }

  // Registers a column; all columns must be registered before the first row.
  void add(std::string name, std::string unit, std::string description, Getter get) {
    signals_.names.push_back(std::move(name));
    signals_.units.push_back(std::move(unit));
    signals_.descriptions.push_back(std::move(description));
    signals_.columns.emplace_back();
    getters_.push_back(std::move(get));
  }

  // Appends one row: every column's getter applied to `state`.
  void record(const State& state) {
    for (std::size_t c = 0; c < getters_.size(); ++c) signals_.columns[c].push_back(getters_[c](state));
  }

  const Signals& signals() const { return signals_; }

 private:
  Signals& signals_;
  std::vector<Getter> getters_;
};

}  // namespace rsw::physics
