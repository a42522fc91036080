#ifndef SPINESIM_COUPLING_SCENE_H
#define SPINESIM_COUPLING_SCENE_H

// A scene: the parameter file that says what a run is. Every parameter of every scenario
// and module is declared up front (ASPECT-style), so `spinesim params` lists them all and a
// scene is checked against the same declarations it runs with.

#include "applications/framework/effects.h"

#include <deal.II/base/parameter_handler.h>

#include <string>
#include <vector>

namespace spinesim::framework {

class Scene {
 public:
  Scene();

  // Reads a .prm or .json scene. Bad input throws InvalidInput naming file, line, parameter
  // path and what is allowed. `include FILE` lines are expanded here (relative to the file
  // that includes; a cycle or more than 16 levels is bad input), and relative values of
  // file parameters (pattern FileName) resolve against the scene file's directory when the
  // file is there (otherwise they stay relative to the working directory).
  void load_file(const std::string& path);
  // Reads scene text (the embedded default scene); `name` stands in for the file name.
  void load_text(const std::string& text, const std::string& name);
  // "Section/Sub/Parameter=value", checked like a file entry.
  void apply_override(const std::string& assignment);

  // Existing files named by file parameters (pattern FileName): what a run reads besides the
  // scene, which --force must never delete.
  std::vector<std::string> input_files() const;

  const dealii::ParameterHandler& prm() const { return prm_; }
  dealii::ParameterHandler& prm() { return prm_; }
  const std::string& source_name() const { return source_name_; }

  int dimension() const;
  std::string scenario() const;
  std::string description() const;
  // Parsed and checked effects.
  Effects effects() const;

  // The fully resolved parameters, as a .prm text (declaration order, with help texts).
  std::string resolved_prm() const;

  // Every declared parameter: format "prm", "json" or "md".
  std::string listing(const std::string& format) const;

 private:
  // Turns a deal.II parse error into InvalidInput with the subsection path and what the
  // subsection allows. `text` is the scene text for locating the line's subsection.
  [[noreturn]] void rethrow_parse_error(const std::string& deal_message,
                                        const std::string& text) const;
  // Relative FileName values that exist below `directory` become paths into it.
  void resolve_file_parameters(const std::string& directory);
  std::string allowed_names(const std::vector<std::string>& path) const;

  dealii::ParameterHandler prm_;
  std::string source_name_ = "(defaults)";
  // Where each line of the parsed text came from ("file:line"), when includes were expanded.
  std::vector<std::string> line_origins_;
};

} // namespace spinesim::framework

#endif
