#include "cli.h"

#include "applications/framework/driver.h"
#include "default_scene.h"

#include <deal.II/base/mpi.h>

#include <CLI/CLI.hpp>

#include <iostream>

namespace spinesim {

int run_cli(int argc, char** argv) {
  using namespace framework;
  CLI::App app{"spinesim: coupled finite-element / meshfree simulation of fracture in bone and "
               "implants.\nExit codes: 0 ok, 1 run failed (divergence, NaN, ...), 2 bad input."};
  app.set_version_flag("--version", std::string("spinesim ") + SPINESIM_VERSION);
  app.require_subcommand(1);

  RunOptions run;
  run.scene.default_text = default_scene_text;
  std::string run_scene, restart_dir;
  auto* run_cmd =
      app.add_subcommand("run", "Run a scene (the embedded default scene without SCENE).");
  run_cmd->add_option("SCENE", run_scene, "Scene file (.prm or .json)");
  run_cmd->add_option("-o,--output", run.output, "Output directory")->capture_default_str();
  run_cmd
      ->add_option("-s,--set", run.scene.overrides,
                   "Override a parameter: \"Section/Sub/Parameter=value\" (repeatable)")
      ->take_all();
  run_cmd->add_option("-t,--threads", run.threads, "Threads per MPI rank (0: all available)")
      ->check(CLI::NonNegativeNumber);
  auto* force_flag =
      run_cmd->add_flag("-f,--force", run.force, "Replace the output directory of an earlier run");
  run_cmd
      ->add_option("--restart", restart_dir,
                   "Continue the run in this output directory from its last checkpoint")
      ->excludes(force_flag);
  run_cmd->add_option("--progress", run.progress, "Progress display")
      ->check(CLI::IsMember({"auto", "bar", "lines", "off"}))
      ->capture_default_str();

  SceneSource params_source;
  params_source.default_text = default_scene_text;
  std::string params_scene, format = "prm";
  auto* params_cmd = app.add_subcommand(
      "params", "List every parameter with its default, pattern, unit and help text "
                "(with SCENE: the values that scene resolves to).");
  params_cmd->add_option("SCENE", params_scene, "Scene file whose values to show");
  params_cmd->add_option("--format", format, "Output format")
      ->check(CLI::IsMember({"prm", "json", "md"}))
      ->capture_default_str();
  params_cmd->add_option("-s,--set", params_source.overrides, "Override a parameter")->take_all();

  SceneSource check_source;
  std::string check_scene;
  auto* check_cmd = app.add_subcommand("check", "Validate a scene without running it.");
  check_cmd->add_option("SCENE", check_scene, "Scene file (.prm or .json)")->required();
  check_cmd->add_option("-s,--set", check_source.overrides, "Override a parameter")->take_all();
  bool estimate = false;
  check_cmd->add_flag("--estimate", estimate,
                      "Also print the model's size and the predicted wall time and peak memory "
                      "of the run (from the cost table the accuracy_cost study fits)");

  // convert: the ct_to_particles scenario on a scene's CT, Bone and Caps sections (a CT
  // scene such as vertebra_compression.prm), through the same run path as `run`.
  RunOptions convert;
  convert.output = "spinesim-particles";
  std::string convert_scene, convert_per = "cell";
  auto* convert_cmd = app.add_subcommand(
      "convert", "Convert the CT model of a scene (sections CT, Bone, Caps) to particles: "
                 "positions, volumes, density and material per cell or Gauss point, written to "
                 "particles.vtu and particles.h5 in the output directory.");
  convert_cmd->add_option("SCENE", convert_scene, "Scene file with a CT section")->required();
  convert_cmd->add_option("-o,--output", convert.output, "Output directory")->capture_default_str();
  convert_cmd->add_option("--per", convert_per, "One particle per cell or per quadrature point")
      ->check(CLI::IsMember({"cell", "quadrature"}))
      ->capture_default_str();
  convert_cmd->add_option("-s,--set", convert.scene.overrides, "Override a parameter")->take_all();
  convert_cmd->add_flag("-f,--force", convert.force,
                        "Replace the output directory of an earlier run");
  convert_cmd->add_option("--progress", convert.progress, "Progress display")
      ->check(CLI::IsMember({"auto", "bar", "lines", "off"}))
      ->capture_default_str();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const bool root = dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
    if (e.get_exit_code() == 0) {
      if (root)
        app.exit(e);
      return exit_ok;
    }
    if (root)
      app.exit(e);
    return exit_bad_input;
  }

  if (*run_cmd) {
    if (!run_scene.empty())
      run.scene.file = run_scene;
    if (!restart_dir.empty()) {
      if (!run_scene.empty()) {
        std::cerr << "spinesim: bad input\n  where:   --restart\n  problem: a restart continues "
                     "the scene of the run it restarts\n  allowed: --restart DIR without SCENE\n";
        return exit_bad_input;
      }
      run.restart_dir = restart_dir;
    }
    return run_command(run);
  }
  if (*params_cmd) {
    if (!params_scene.empty())
      params_source.file = params_scene;
    return params_command(params_source, format);
  }
  if (*convert_cmd) {
    convert.scene.file = convert_scene;
    convert.scene.overrides.push_back("Scenario=ct_to_particles");
    convert.scene.overrides.push_back("Particle conversion/Per=" + convert_per);
    return run_command(convert);
  }
  check_source.file = check_scene;
  return check_command(check_source, estimate);
}

} // namespace spinesim
