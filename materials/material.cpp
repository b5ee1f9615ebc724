// Material properties, strength floor and enthalpy (equations in material.hpp).
#include "materials/material.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace rsw::materials {
namespace {

void require(bool condition, const MaterialData& data, const std::string& what) {
  if (!condition) {
    throw std::invalid_argument("material '" + data.name + "'" +
                                (data.source_file.empty() ? "" : " (" + data.source_file + ")") +
                                ": " + what);
  }
}

bool all_positive(const PropertyTable& table) {
  const auto& v = table.values();
  return std::all_of(v.begin(), v.end(), [](double x) { return x > 0; });
}

}  // namespace

PropertyValue smoothstep(double x, double lower, double upper) {
  const double width = upper - lower;
  const double s = (x - lower) / width;
  if (s <= 0) return {0.0, 0.0};
  if (s >= 1) return {1.0, 0.0};
  return {s * s * (3 - 2 * s), 6 * s * (1 - s) / width};
}

Material::Material(MaterialData data) : data_(std::move(data)) {
  require(!data_.name.empty(), data_, "has no name");
  require(all_positive(data_.electrical_resistivity), data_,
          "electrical resistivity must be positive");
  require(all_positive(data_.thermal_conductivity), data_,
          "thermal conductivity must be positive");
  require(all_positive(data_.specific_heat), data_, "specific heat must be positive");
  require(all_positive(data_.density), data_, "density must be positive");
  require(all_positive(data_.youngs_modulus), data_, "Young's modulus must be positive");
  for (double nu : data_.poisson_ratio.values()) {
    require(nu >= 0 && nu < 0.5, data_, "Poisson ratio must lie in [0, 0.5)");
  }
  for (double alpha : data_.secant_expansion.values()) {
    require(alpha > -1e-3 && alpha < 1e-3, data_,
            "secant expansion coefficient must be a small number per kelvin");
  }
  for (double eta : data_.flow_viscosity.values()) {
    require(std::isfinite(eta) && eta >= 0, data_, "flow viscosity must be >= 0");
  }
  require(!data_.flow_curves.empty(), data_, "has no flow curves");
  require(std::isfinite(data_.solidus) && std::isfinite(data_.liquidus) &&
              data_.liquidus > data_.solidus,
          data_, "liquidus must lie above the solidus");
  require(std::isfinite(data_.melting_temperature), data_,
          "melting temperature must be finite");
  require(std::isfinite(data_.latent_heat) && data_.latent_heat >= 0, data_,
          "latent heat must be >= 0");
  require(std::isnan(data_.boiling_point) || data_.boiling_point > data_.liquidus, data_,
          "boiling point must lie above the liquidus");
  require(std::isfinite(data_.strength_floor) && data_.strength_floor > 0, data_,
          "strength floor must be positive");
  require(std::isfinite(data_.strength_floor_transition) &&
              data_.strength_floor_transition > 0,
          data_, "strength floor transition must be positive");
}

PropertyValue Material::electrical_resistivity(double temperature) const {
  return data_.electrical_resistivity.evaluate(temperature);
}

PropertyValue Material::thermal_conductivity(double temperature) const {
  return data_.thermal_conductivity.evaluate(temperature);
}

PropertyValue Material::specific_heat(double temperature) const {
  return data_.specific_heat.evaluate(temperature);
}

PropertyValue Material::density(double temperature) const {
  return data_.density.evaluate(temperature);
}

PropertyValue Material::youngs_modulus(double temperature) const {
  return data_.youngs_modulus.evaluate(temperature);
}

PropertyValue Material::poisson_ratio(double temperature) const {
  return data_.poisson_ratio.evaluate(temperature);
}

PropertyValue Material::flow_viscosity(double temperature) const {
  return data_.flow_viscosity.evaluate(temperature);
}

PropertyValue Material::secant_expansion(double temperature) const {
  return data_.secant_expansion.evaluate(temperature);
}

PropertyValue Material::thermal_strain(double temperature,
                                       double stress_free_temperature) const {
  const PropertyValue alpha = secant_expansion(temperature);
  const double alpha_0 = secant_expansion(stress_free_temperature).value;
  const double rise = temperature - reference_temperature;
  // α(T)(T − T_ref) − α_0 (T_0 − T_ref), written as (α(T) − α_0)(T − T_ref) + α_0 (T − T_0):
  // exactly zero at T = T_0 however the products are rounded (a fused multiply-add
  // leaves the rounding error of one of two equal products otherwise), and without
  // the cancellation of two large terms near T_0.
  return {(alpha.value - alpha_0) * rise + alpha_0 * (temperature - stress_free_temperature),
          alpha.slope * rise + alpha.value};
}

FlowStress Material::yield_stress(double equivalent_plastic_strain, double temperature) const {
  const FlowStress table = data_.flow_curves.evaluate(equivalent_plastic_strain, temperature);
  const PropertyValue w = smoothstep(temperature, data_.solidus - data_.strength_floor_transition,
                                     data_.solidus);
  const double floor = data_.strength_floor;
  return {(1 - w.value) * table.yield_stress + w.value * floor,
          (1 - w.value) * table.hardening,
          (1 - w.value) * table.temperature_slope + w.slope * (floor - table.yield_stress)};
}

PropertyValue Material::liquid_fraction(double temperature) const {
  return smoothstep(temperature, data_.solidus, data_.liquidus);
}

PropertyValue Material::enthalpy(double temperature) const {
  const PropertyValue f = liquid_fraction(temperature);
  const double sensible = data_.specific_heat.integral(reference_temperature, temperature);
  return {sensible + data_.latent_heat * f.value,
          specific_heat(temperature).value + data_.latent_heat * f.slope};
}

}  // namespace rsw::materials
