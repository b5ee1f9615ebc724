// `rsw mesh`: weld case -> one quadtree mesh per body -> DIR/mesh.vtm (+ DIR/mesh/*.vtu,
// *_boundaries.vtp), with a size/quality report on stdout.
#include "tools/mesh_command.hpp"

#include "fem/vtk_output.hpp"
#include "meshes/weld_mesh.hpp"
#include "physics/problem.hpp"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace rsw::tools {

namespace {

struct MeshOptions {
  std::string case_file;
  std::string output_dir;
  std::vector<std::string> overrides;
};

void print_stats_row(const std::string& name, const fem::MeshStats& s) {
  std::printf("  %-18s %7d %7d %7d   %7.4f  %7.4f   %6.3f   %5.1f..%5.1f\n", name.c_str(), s.n_cells, s.n_nodes,
              s.n_hanging, s.min_edge * 1e3, s.max_edge * 1e3, s.min_scaled_jacobian, s.min_angle_deg,
              s.max_angle_deg);
}

void run_mesh(const MeshOptions& options) {
  const physics::Problem problem = physics::load_problem(options.case_file, options.overrides);
  const fem::Mesh mesh = meshes::weld_mesh(problem.geometry, problem.mesh);

  const std::filesystem::path dir = options.output_dir.empty() ? problem.output.directory : options.output_dir;
  const std::filesystem::path vtm = dir / "mesh.vtm";
  fem::write_vtm(vtm, mesh);

  std::printf("mesh of %s\n", options.case_file.c_str());
  std::printf("  %-18s %7s %7s %7s   %7s  %7s   %6s   %s\n", "body", "cells", "nodes", "hanging", "min edge",
              "max edge", "min SJ", "angles (deg)");
  std::printf("  %-18s %7s %7s %7s   %7s  %7s\n", "", "", "", "", "(mm)", "(mm)");
  for (int b = 0; b < mesh.n_bodies(); ++b) print_stats_row(mesh.body_names[b], fem::mesh_stats(mesh, b));
  print_stats_row("all", fem::mesh_stats(mesh));

  // Element size in the weld zone, measured per body on the cells whose centre lies in it.
  const auto zone = meshes::refinement_boxes(problem.geometry, problem.mesh).front();
  std::printf("weld zone r <= %.3g mm, |z| <= %.3g mm, %d levels (nominal edge %.4f mm):\n", zone.r_max * 1e3,
              zone.z_max * 1e3, zone.levels, problem.mesh.base_size / (1 << zone.levels) * 1e3);
  for (int b = 0; b < mesh.n_bodies(); ++b) {
    double min_edge = 1e300, max_edge = 0;
    int n_zone = 0;
    for (int e = 0; e < mesh.n_cells(); ++e) {
      if (mesh.cell_body[e] != b) continue;
      const auto& c = mesh.cells[e];
      const fem::Point centre = 0.25 * (mesh.nodes[c[0]] + mesh.nodes[c[1]] + mesh.nodes[c[2]] + mesh.nodes[c[3]]);
      if (centre.x() < zone.r_min || centre.x() > zone.r_max || centre.y() < zone.z_min || centre.y() > zone.z_max)
        continue;
      ++n_zone;
      for (int k = 0; k < 4; ++k) {
        const double len = (mesh.nodes[c[(k + 1) % 4]] - mesh.nodes[c[k]]).norm();
        min_edge = std::min(min_edge, len);
        max_edge = std::max(max_edge, len);
      }
    }
    if (n_zone > 0)
      std::printf("  %-18s %6d cells, edges %.4f..%.4f mm\n", mesh.body_names[b].c_str(), n_zone, min_edge * 1e3,
                  max_edge * 1e3);
  }
  std::printf("min SJ: worst scaled Jacobian (sine of the worst corner angle; 1 = rectangle). Electrode cells\n"
              "in the weld zone deviate from the nominal edge where the mesh follows the dome and the flank.\n");
  std::printf("wrote %s (open in ParaView)\n", vtm.string().c_str());
}

}  // namespace

void add_mesh_command(CLI::App& app) {
  auto options = std::make_shared<MeshOptions>();
  CLI::App* cmd = app.add_subcommand("mesh", "Build the meshes of a weld case and write them for ParaView");
  cmd->add_option("case", options->case_file, "Weld-case YAML file")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", options->output_dir, "Output folder (default: the case's output.directory)");
  cmd->add_option("--set", options->overrides, "Override a config key: --set key=value (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
  cmd->callback([options]() { run_mesh(*options); });
}

}  // namespace rsw::tools
