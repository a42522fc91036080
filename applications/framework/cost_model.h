#ifndef SPINESIM_APPLICATIONS_FRAMEWORK_COST_MODEL_H
#define SPINESIM_APPLICATIONS_FRAMEWORK_COST_MODEL_H

// What a run will cost before it runs. A scenario states, once its model is built, the kind of
// work it does (e.g. fem_quasi_static, coupled_explicit:bond_based), how much (work units:
// DoF-solves, (DoF + bond)-steps, ...) and its state size (unknowns and bonds). The cost
// table holds per kind a law of the run's wall time in the work, t = t0 + a W^b (t0 the fixed
// cost of any run of the kind), and a linear law of the peak memory in the state size,
// m = m0 + m1 N, fitted by the
// accuracy-versus-cost study on measured runs (applications/studies/cost_model.json,
// compiled in; docs/accuracy-cost.md).

#include <map>
#include <optional>
#include <string>

namespace spinesim::framework {

struct RunCost {
  std::string kind; // empty: the scenario states none
  double work = 0;  // work units of the kind
  double state = 0; // unknowns + bonds held
  // What the state is made of (0: none in this run), over all ranks.
  double fem_dofs = 0;          // displacement DoFs of the FEM mechanics
  double heat_dofs = 0;         // temperature DoFs
  double particles = 0;         // particles that carry their own unknowns ...
  double particle_unknowns = 0; // ... and those unknowns (dim per particle)
  double bonds = 0;             // particle bonds (each counted once)
  double meshfree_unknowns = 0; // unknowns of a meshfree Galerkin (LSMFM) discretisation

  // "N unknowns and bonds: a FEM DoFs, b particles (c unknowns), d bonds, ..."; the parts are
  // named only when the scenario stated them.
  std::string describe_state() const;
};

struct CostLaw {
  double time_offset = 0;                         // t0 [s]
  double time_coefficient = 0, time_exponent = 1; // t = t0 + a W^b [s]
  double memory_base = 0, memory_per_state = 0;   // m = m0 + m1 N [MiB]
  unsigned int runs = 0;                          // measured runs the laws were fitted to
  double work_min = 0, work_max = 0;              // range of W they cover
};

struct CostPrediction {
  double wall_time = 0;   // [s]
  double peak_memory = 0; // [MiB]
  const CostLaw* law = nullptr;
  bool extrapolated = false; // W outside the fitted range
};

class CostModel {
 public:
  // The table compiled into the program.
  static const CostModel& built_in();
  static CostModel from_json(const std::string& text);
  std::string to_json() const;

  void set(const std::string& kind, const CostLaw& law) { laws_[kind] = law; }
  std::optional<CostPrediction> predict(const RunCost& cost) const;
  const std::map<std::string, CostLaw>& laws() const { return laws_; }

 private:
  std::map<std::string, CostLaw> laws_;
};

} // namespace spinesim::framework

#endif
