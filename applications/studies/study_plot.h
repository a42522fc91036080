#ifndef SPINESIM_APPLICATIONS_STUDIES_STUDY_PLOT_H
#define SPINESIM_APPLICATIONS_STUDIES_STUDY_PLOT_H

// The picture of one problem of an accuracy-versus-cost study: error against median wall
// time on log–log axes, one series per method (points in order of resolution), the Pareto
// front drawn through the runs no other run beats in both. Drawn by gnuplot (Debian
// gnuplot-nox) from a script written beside the PNG.

#include "applications/framework/run_context.h"
#include "applications/studies/study_table.h"

#include <filesystem>
#include <string>
#include <vector>

namespace spinesim::applications {

// The gnuplot script that draws `png` (a file name in the script's directory) from the rows
// of `problem`.
// `time_label` names the time measure on the abscissa.
std::string accuracy_cost_script(const std::string& problem, const std::vector<StudyRow>& rows,
                                 const std::string& png, const std::string& time_label);

// Draws <name>.png in the run's output directory: writes the gnuplot commands `script` (which
// set the output to that file) to <name>.gp, runs gnuplot with its log in <name>.gnuplot.log,
// and returns 1 for a valid PNG, 0 for none or a broken one (with a warning naming the log),
// NaN without gnuplot (a warning names the package and `data`, where the numbers are).
// Collective in name only: call it on the root rank.
double draw_with_gnuplot(framework::RunContext& ctx, const std::string& name,
                         const std::string& script, const std::string& data);

// Whether `file` is a PNG image: the signature, an IHDR chunk with a non-zero size first and
// an IEND chunk last (a truncated or empty plot fails).
bool png_is_valid(const std::filesystem::path& file);

} // namespace spinesim::applications

#endif
