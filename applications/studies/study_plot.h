#ifndef SPINESIM_APPLICATIONS_STUDIES_STUDY_PLOT_H
#define SPINESIM_APPLICATIONS_STUDIES_STUDY_PLOT_H

// The picture of one problem of an accuracy-versus-cost study: error against median wall
// time on log–log axes, one series per method (points in order of resolution), the Pareto
// front drawn through the runs no other run beats in both. Drawn by gnuplot (Debian
// gnuplot-nox) from a script written beside the PNG.

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

// Whether `file` is a PNG image: the signature, an IHDR chunk with a non-zero size first and
// an IEND chunk last (a truncated or empty plot fails).
bool png_is_valid(const std::filesystem::path& file);

} // namespace spinesim::applications

#endif
