#ifndef SPINESIM_APPLICATIONS_STUDIES_STUDY_TABLE_H
#define SPINESIM_APPLICATIONS_STUDIES_STUDY_TABLE_H

// The rows of an accuracy-versus-cost study and what is read off them: medians and spreads of
// the repeated timings, the Pareto front per problem (no other run is both faster and more
// accurate), the observed convergence order per method, and the CSV and Markdown tables.

#include "applications/framework/cost_model.h"

#include <map>
#include <string>
#include <vector>

namespace spinesim::applications {

struct StudyRow {
  std::string problem, method;         // e.g. cantilever, fem_q1
  std::string parameter, value;        // the resolution parameter and its value in this run
  unsigned int case_index = 0;         // 1-based Case slot of the study scene
  double h = 0;                        // the size figure of the run
  std::string h_unit;                  // its unit in summary.json (m, mm)
  double cells = 0, particles = 0;     // FEM cells, particles the method solves for
  double unknowns = 0;                 // dim × particles + FEM DoFs
  double quantity = 0;                 // the case's error figure as the run reported it
  double error = 0;                    // its error: the quantity itself, or against the reference
  bool is_reference = false;           // the finest run of a case measured against its finest
  bool cost_only = false;              // a run that calibrates the cost table only (no error)
  std::string cost_kind;               // the run's stated work (summary.json "run")
  double work = 0, state = 0;          // its work units and state size
  std::vector<double> predicted_times; // the built-in cost table's prediction per repetition [s]
  // Per repetition [s]: the time the study compares (Time measure: the run's own wall time,
  // summary.json timings/total, or the process's), and the process's wall time from spawn to
  // exit (start-up, MPI initialisation and library loading included).
  std::vector<double> wall_times;
  std::vector<double> process_times;
  std::vector<double> peak_rss_mb; // per repetition [MiB]
  std::vector<double> loads;       // 1-minute load average at each start [-]
  unsigned int threads = 1, ranks = 1;
  std::string status = "not run"; // ok | failed (exit 1) | bad input (exit 2) | ...
  std::string run_directory;      // relative to the study's directory
  bool pareto = false;

  double wall_time() const;      // median [s]
  double process_time() const;   // median [s]
  double time_spread() const;    // (max − min) / median [-]
  double peak_rss() const;       // median [MiB]
  double load() const;           // median [-]
  double predicted_time() const; // median [s]
  bool finite() const;           // ok with finite, positive error, size and time
};

double median(std::vector<double> values);

// Marks the Pareto front of each problem among the finite rows.
void mark_pareto_fronts(std::vector<StudyRow>& rows);

struct RateFit {
  double order = 0;         // slope of log(error) against log(h), least squares
  unsigned int points = 0;  // finite rows fitted
  bool errors_fall = false; // the error falls at every refinement (rows by falling h)
  double finest_error = 0;  // error of the smallest h
};
// The rows of one case (same problem and method), any order.
RateFit fit_rate(std::vector<const StudyRow*> rows);

std::string study_csv(const std::vector<StudyRow>& rows);

// Per kind of work, the power law of the median run time in the work units and the linear law
// of the peak memory in the state size, by least squares over the rows that state the kind
// (cost-only and reference rows included).
class CostFit {
 public:
  static std::map<std::string, framework::CostLaw> fit(const std::vector<StudyRow>& rows);
};

} // namespace spinesim::applications

#endif
