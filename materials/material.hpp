// One material: temperature-dependent properties, flow stress with a strength floor
// for molten material, thermal strain, and enthalpy with latent heat of fusion.
// Every accessor is a pure function of the state (T, eps_p) returning the value and
// its derivative; SI units, temperatures in degC.
//
// Thermal strain (secant expansion coefficient alpha(T) measured from the reference
// temperature T_r = 20 degC, the convention of EN 1993-1-2 and of most data sheets):
//     eps_th(T; T_0) = alpha(T) (T - T_r) - alpha(T_0) (T_0 - T_r),
// zero at the stress-free temperature T_0, so no strain appears at T = T_0 whatever
// alpha(T_0) is.
//
// Yield stress above the solidus: molten metal has no strength, but a small floor
// sigma_floor keeps the mechanical system solvable. The tabulated flow stress blends
// into the floor over the band [T_s - dT, T_s] (dT = strength_floor_transition):
//     sigma_y = (1 - w) sigma_table(eps_p, T) + w sigma_floor,
//     w = 3 s^2 - 2 s^3,  s = clamp((T - T_s + dT) / dT, 0, 1),
// a C^1 blend (w and dw/dT continuous), so sigma_y equals the floor at and above the
// solidus and the table at and below T_s - dT; the hardening modulus is scaled by
// (1 - w), vanishing in the melt (perfectly plastic floor).
//
// Rate dependence of plastic flow (a Perzyna overstress law with exponent 1, used by
// materials/j2_plasticity): above yield the equivalent stress exceeds the flow stress
// by eta(T) times the equivalent plastic strain rate, q = sigma_y + eta d(eps_bar_p)/dt;
// flow_viscosity(T) returns eta in Pa*s. eta = 0 is rate-independent plasticity.
//
// Enthalpy per unit mass relative to T_r (for an enthalpy or apparent-heat-capacity
// thermal integrator):
//     h(T) = integral_{T_r}^{T} c_p dT' + L f_l(T),
//     f_l(T) = 3 s^2 - 2 s^3,  s = clamp((T - T_s) / (T_l - T_s), 0, 1),
// with c_p the sensible specific heat table, L the latent heat of fusion and f_l the
// liquid fraction (smooth between solidus T_s and liquidus T_l, so dh/dT, the
// apparent heat capacity, is continuous). h is a function of T alone, so an
// integrator that updates h conserves energy exactly: heating from below T_s to above
// T_l absorbs integral c_p dT + L.
//
// The paper's modified conductivity (k = lambda_m at and above T_melting, paper eq. 3)
// is not applied here: lambda_m is a model parameter owned by the physics layer;
// thermal_conductivity() is the tabulated k(T), and melting_temperature() gives the
// switch point.
//
// Sources of the shipped data are cited in materials/data/*.yaml.
#pragma once

#include "materials/property_table.hpp"

#include <cmath>
#include <string>

namespace rsw::materials {

// Temperature from which secant expansion and enthalpy are measured, degC.
inline constexpr double reference_temperature = 20.0;

// Everything that defines a material, in SI units (temperatures in degC).
struct MaterialData {
  std::string name;
  std::string description;
  std::string source_file;  // the data file it came from; empty if built in code

  PropertyTable electrical_resistivity;  // ohm*m
  PropertyTable thermal_conductivity;    // W/(m*K)
  PropertyTable specific_heat;           // J/(kg*K), sensible heat only
  PropertyTable density;                 // kg/m^3
  PropertyTable youngs_modulus;          // Pa
  PropertyTable poisson_ratio;           // -
  PropertyTable secant_expansion;        // 1/K, secant from reference_temperature
  PropertyTable flow_viscosity = PropertyTable::constant(0.0);  // Pa*s, eta of the overstress law
  FlowCurveTable flow_curves;            // Pa against eps_p and degC

  double solidus = 0;                    // degC
  double liquidus = 0;                   // degC
  double melting_temperature = 0;        // degC, T_melting of paper eq. 3
  double latent_heat = 0;                // J/kg
  double boiling_point = std::nan("");   // degC, at 1 atm; NaN: not given
  double strength_floor = 0;             // Pa, yield stress of the melt
  double strength_floor_transition = 50; // K, width of the blend below the solidus
};

class Material {
 public:
  // Checks the data (positive properties, 0 <= nu < 0.5, solidus < liquidus, ...);
  // throws std::invalid_argument naming the material and the property.
  explicit Material(MaterialData data);

  const std::string& name() const { return data_.name; }
  const MaterialData& data() const { return data_; }

  PropertyValue electrical_resistivity(double temperature) const;  // ohm*m
  PropertyValue thermal_conductivity(double temperature) const;    // W/(m*K), table
  PropertyValue specific_heat(double temperature) const;           // J/(kg*K), sensible
  PropertyValue density(double temperature) const;                 // kg/m^3
  PropertyValue youngs_modulus(double temperature) const;          // Pa
  PropertyValue poisson_ratio(double temperature) const;           // -
  PropertyValue secant_expansion(double temperature) const;        // 1/K
  PropertyValue flow_viscosity(double temperature) const;          // Pa*s, eta(T)

  // eps_th(T; T_0) and d eps_th / dT (1/K); T_0 is the stress-free temperature.
  PropertyValue thermal_strain(double temperature, double stress_free_temperature) const;

  // Yield stress with the strength floor blended in below the solidus; hardening and
  // temperature slope are the exact derivatives of the blended value.
  FlowStress yield_stress(double equivalent_plastic_strain, double temperature) const;

  // Liquid fraction f_l in [0, 1] and d f_l / dT.
  PropertyValue liquid_fraction(double temperature) const;
  // h(T) in J/kg relative to 20 degC, and dh/dT (apparent heat capacity, J/(kg*K)).
  PropertyValue enthalpy(double temperature) const;

  double solidus() const { return data_.solidus; }                  // degC
  double liquidus() const { return data_.liquidus; }                // degC
  double melting_temperature() const { return data_.melting_temperature; }  // degC
  double latent_heat() const { return data_.latent_heat; }          // J/kg
  double boiling_point() const { return data_.boiling_point; }      // degC; NaN where the file gives none
  double strength_floor() const { return data_.strength_floor; }    // Pa
  double strength_floor_transition() const { return data_.strength_floor_transition; }  // K

 private:
  MaterialData data_;
};

// 3 s^2 - 2 s^3 on s = clamp((x - lower) / (upper - lower), 0, 1) and its derivative
// with respect to x; the blend used for the liquid fraction and the strength floor.
PropertyValue smoothstep(double x, double lower, double upper);

}  // namespace rsw::materials
