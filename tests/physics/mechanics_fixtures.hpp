// Shared set-up for the mechanics tests: simple meshes and elastic materials.
#pragma once

#include "fem/quadtree.hpp"
#include "materials/material.hpp"
#include "materials/material_library.hpp"

#include <string>

namespace rsw::test {

// Rectangle r in [r0, r1], z in [z0, z1] (m) with base cells of size h, refined
// `levels` times where refine(x, y) (index box lower corner) says so. Boundaries
// "<body>.bottom/.right/.top/.left"; the left side is "<body>.axis" when r0 == 0.
inline fem::Mesh block_mesh(const std::string& body, double r0, double r1, double z0, double z1, double h,
                            int levels = 0,
                            std::function<bool(const fem::IndexBox&)> refine = {}) {
  const int n_r = static_cast<int>(std::lround((r1 - r0) / h));
  const int n_z = static_cast<int>(std::lround((z1 - z0) / h));
  fem::Quadtree tree(n_r, n_z);
  if (levels > 0 && refine) tree.refine([&](const fem::IndexBox& b) { return refine(b) ? levels : 0; });
  tree.balance();
  return tree.build(
      body, [=](double x, double y) { return fem::Point(r0 + (r1 - r0) * x / n_r, z0 + (z1 - z0) * y / n_z); },
      [r0](double, double, fem::Side s) -> std::string {
        switch (s) {
          case fem::Side::bottom: return "bottom";
          case fem::Side::right: return "right";
          case fem::Side::top: return "top";
          case fem::Side::left: return r0 == 0 ? "axis" : "left";
        }
        return "";
      });
}

// A purely elastic copy of a material: constant E, ν, α and a yield stress so high
// that no test load reaches it.
inline materials::Material elastic_material(const std::string& name, double E, double nu, double alpha) {
  materials::MaterialData d = materials::MaterialLibrary().load("DP1200").data();
  d.name = name;
  d.youngs_modulus = materials::PropertyTable::constant(E);
  d.poisson_ratio = materials::PropertyTable::constant(nu);
  d.secant_expansion = materials::PropertyTable::constant(alpha);
  d.flow_curves = materials::FlowCurveTable({{20.0, {0.0, 1.0}, {1e13, 1e13}}});
  return materials::Material(d);
}

}  // namespace rsw::test
