// The `lsmfm` scenario: a quasi-static elasto-plastic run with the least-squares meshfree
// method of Kwon & Youn (2005) (meshfree/lsmfm/lsmfm_solver.h).
//
// The nodes are the vertices of the scene's mesh (Geometry section; the paper's regular node
// distribution of Fig. 7a), optionally jittered (its irregular distribution, Fig. 7b). The
// functional is integrated by support integration (eq. 100, no cells) or by Gauss points on
// the mesh cells (the paper's "LSMFM 1", element integration). Boundary conditions come from
// Mechanics/Boundary conditions, the same slots the FEM reads: a Dirichlet slot becomes
// displacement conditions at its boundary nodes; every boundary node gets the traction
// conditions (σn)·e_d = t̄_d for the components no Dirichlet slot holds there (0 on free
// boundaries; the Traction and Pressure slots give t̄) — the least-squares functional has no
// natural boundary conditions, so a free boundary must be imposed too.
//
// Reports, as the scene asks: the displacement error against a known solution, the relative
// difference to the FEM solution of the same scene on the same mesh (eq. 101, Table 2), and
// the homogeneous response at reference stretches (Table 1: flow stress = Cauchy von Mises,
// effective plastic strain, volume averages).

#include "applications/common_sections.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "applications/studies/child_run.h"
#include "applications/studies/study_plot.h"
#include "applications/validation/lsmfm_material.h"
#include "applications/validation/stretch_reference.h"
#include "base/error_sums.h"
#include "base/exceptions.h"
#include "base/expression_function.h"
#include "fem/materials/law_parameters.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"
#include "meshfree/lsmfm/lsmfm_solver.h"
#include "meshfree/lsmfm/support_integration.h"
#include "meshfree/particle_output.h"
#include "meshfree/particle_set.h"

#include <deal.II/base/quadrature_lib.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/fe/fe_q.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_q1.h>
#include <deal.II/grid/grid_tools.h>
#include <deal.II/grid/grid_tools_cache.h>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <sstream>

namespace spinesim::applications {

using namespace framework;

namespace {

struct LsmfmRunParameters {
  double end_time = 1.0;
  unsigned int steps = 1;
  double node_jitter = 0;
  unsigned int seed = 1;
  std::string exact_displacement;
  bool compare_fem = false;
  bool plastic_zone_plot = true;
  int reaction_boundary_id = -1;
  StretchReference reference;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("End time", "1", Double(0.0),
                      "Pseudo-time of the last load step; boundary expressions see t [s].");
    prm.declare_entry("Steps", "1", Integer(1), "Load steps to the end time [-].");
    prm.declare_entry("Node jitter", "0", Double(0.0, 0.4),
                      "Random offset of every interior node per direction, over its spacing: "
                      "an irregular node distribution (Kwon & Youn, Fig. 7b) [-].");
    prm.declare_entry("Seed", "1", Integer(0), "Random seed of the node jitter [-].");
    prm.declare_entry("Exact displacement", "", Anything(),
                      "A known solution, dim ';'-separated expressions in x, y, z and t: "
                      "summary.json then has displacement_l2_error_relative at the end time "
                      "(Gauss rule on the mesh cells); empty = none [m].");
    prm.declare_entry("Compare with FEM", "false", Bool(),
                      "Also solve the scene with the FEM on the same mesh (Mechanics section) "
                      "and report relative_difference_vs_fem = |u_LSMFM − u_FEM| / |u_FEM| in "
                      "L2 (Kwon & Youn, eq. 101) [-].");
    prm.declare_entry("Plastic zone plot", "true", Bool(),
                      "With the FEM comparison, draw plastic_zone.png (gnuplot): the plastic "
                      "points of both solutions side by side [-].");
    prm.declare_entry("Reaction boundary id", "-1", Integer(-1),
                      "Boundary id whose load is reported: reaction_force_norm = |∫ σ^h n da| "
                      "over its faces (Gauss rule, the LSMFM's own stress field; the current "
                      "area in finite strain, by Nanson's formula), per step in "
                      "history.csv, and with the FEM comparison fem_reaction_force_norm; "
                      "-1 = none [N, per unit thickness in 2-D].");
    StretchReference::declare(prm);
  }
  void parse(const dealii::ParameterHandler& prm) {
    end_time = prm.get_double("End time");
    steps = prm.get_integer("Steps");
    node_jitter = prm.get_double("Node jitter");
    seed = prm.get_integer("Seed");
    exact_displacement = prm.get("Exact displacement");
    compare_fem = prm.get_bool("Compare with FEM");
    plastic_zone_plot = prm.get_bool("Plastic zone plot");
    reaction_boundary_id = prm.get_integer("Reaction boundary id");
    reference.parse(prm, "LSMFM run");
    if (!(end_time > 0))
      throw InvalidInput("LSMFM run/End time", "must be positive", "a time > 0 [s]");
  }
};

// A boundary node: its outward normal on each boundary id it lies on.
template <int dim>
struct BoundaryNode {
  unsigned int node;
  std::map<dealii::types::boundary_id, dealii::Tensor<1, dim>> normals;
};

// Outward unit normal of a boundary face of a Q1 cell.
template <int dim>
dealii::Tensor<1, dim>
face_normal(const typename dealii::Triangulation<dim>::active_cell_iterator& cell, unsigned int f) {
  const auto face = cell->face(f);
  dealii::Tensor<1, dim> n;
  if constexpr (dim == 2) {
    const auto t = face->vertex(1) - face->vertex(0);
    n[0] = t[1];
    n[1] = -t[0];
  } else {
    n = dealii::cross_product_3d(face->vertex(3) - face->vertex(0),
                                 face->vertex(2) - face->vertex(1));
  }
  if (n * (face->center() - cell->center()) < 0)
    n = -n;
  return n / n.norm();
}

template <int dim>
class LsmfmScenario : public Scenario {
 public:
  explicit LsmfmScenario(const ScenarioFactoryArgs& args) {
    dealii::ParameterHandler& prm = args.prm;
    parse_section(prm, "Geometry", mesh_);
    parse_section(prm, "Material", law_);
    parse_section(prm, "Mechanics", mech_);
    parse_section(prm, "LSMFM", lsmfm_);
    parse_section(prm, "LSMFM run", run_);
    material_ =
        lsmfm_material<dim>(law_, "linear_elastic|j2_plasticity|j2_finite_strain", "the LSMFM");
    if (mech_.time_integration != "quasi_static")
      throw InvalidInput("Mechanics/Time integration", "'" + mech_.time_integration + "'",
                         "quasi_static: the LSMFM is a static method");
    lsmfm_.plane_model = mech_.plane_stress ? "plane_stress" : "plane_strain";
    lsmfm_.kinematics = mech_.kinematics;
    lsmfm_.validate();
    if (!run_.exact_displacement.empty())
      exact_ = parse_expressions<dim>(run_.exact_displacement, "LSMFM run/Exact displacement", dim,
                                      true, "[m]");
    bcs_.add(mech_.boundary_conditions, "Mechanics/Boundary conditions");
  }

  bool check_by_building() const override { return true; }

  void run(RunContext& ctx) override {
    require_one_lsmfm_rank(ctx.n_ranks());
    dealii::parallel::distributed::Triangulation<dim> tria(ctx.comm());
    dealii::MappingQ1<dim> mapping;
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "setup");
      fem::build_mesh(mesh_, tria);
      make_nodes(tria);
    }
    if (run_.reaction_boundary_id >= 0) {
      const auto ids = tria.get_boundary_ids();
      const auto id = static_cast<dealii::types::boundary_id>(run_.reaction_boundary_id);
      if (std::find(ids.begin(), ids.end(), id) == ids.end()) {
        std::ostringstream allowed;
        for (const auto id : ids)
          allowed << (allowed.tellp() > 0 ? ", " : "") << id;
        throw InvalidInput("LSMFM run/Reaction boundary id",
                           "= " + std::to_string(run_.reaction_boundary_id) +
                               ": no face of the mesh has it",
                           "-1 or a boundary id of the geometry: " + allowed.str());
      }
    }
    const auto rule = integration_rule(tria, mapping);
    std::unique_ptr<meshfree::LsmfmSolver<dim>> solver;
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "setup");
      solver = std::make_unique<meshfree::LsmfmSolver<dim>>(lsmfm_, material_, nodes_, spacing_,
                                                            rule.points, rule.weights);
    }
    ctx.log() << "  LSMFM: " << nodes_.size() << " nodes (" << boundary_.size()
              << " on the boundary), " << rule.points.size() << " integration points ("
              << lsmfm_.integration << "), " << solver->n_unknowns() << " unknowns, "
              << lsmfm_.kinematics << (dim == 2 ? ", " + lsmfm_.plane_model : std::string())
              << "\n  material: " << law_.describe() << "\n";
    // CHOLMOD's supernodal factorisation runs num_threads(4) regions compiled in
    // (cholmod_core.h, CHOLMOD_OMP_NUM_THREADS); only OMP_THREAD_LIMIT, read at start-up,
    // caps them (measured: 4 threads on 2 cores made a 1-thread run 20 % slower).
    if (omp_get_thread_limit() > omp_get_max_threads())
      ctx.log() << "  note: the sparse Cholesky (CHOLMOD) may run up to 4 OpenMP threads "
                   "whatever --threads says; start with OMP_THREAD_LIMIT="
                << omp_get_max_threads() << " to cap it (studies do)\n";

    // The cost table's work: unknowns × load steps (each step a few sparse factorisations).
    framework::RunCost cost{"lsmfm_quasi_static", double(solver->n_unknowns()) * run_.steps,
                            double(solver->n_unknowns())};
    cost.meshfree_unknowns = solver->n_unknowns();
    ctx.set_cost(cost);

    std::unique_ptr<fem::MechanicsSolver<dim>> fem;
    if (run_.compare_fem) {
      dealii::TimerOutput::Scope t(ctx.timer(), "fem setup");
      fem = std::make_unique<fem::MechanicsSolver<dim>>(tria, mech_);
      fem->set_material(0, materials::create_law(law_));
      fem->setup();
    }

    std::vector<bool> reached(run_.reference.stretch.size(), false);
    std::vector<std::array<double, 2>> at_reference(reached.size());
    unsigned int newton = 0, max_newton = 0;
    double min_line_search = 1, max_yield_violation = 0;
    unsigned int set_fallbacks = 0;
    // The load on Reaction boundary id at the last step; NaN when none is asked for (the
    // history column then says so).
    double reaction = std::numeric_limits<double>::quiet_NaN();
    ctx.history().add({{"time", 0.0},
                       {"stretch", 1.0},
                       {"flow_stress_MPa", 0.0},
                       {"eff_plastic_strain", 0.0},
                       {"iterations", 0.0},
                       {"functional", 0.0},
                       {"plastic_points", 0.0},
                       {"reaction_force", run_.reaction_boundary_id >= 0 ? 0.0 : reaction}});
    ctx.progress().start("LSMFM", run_.steps, run_.end_time);
    for (unsigned int step = 1; step <= run_.steps; ++step) {
      const double t = run_.end_time * step / run_.steps;
      typename meshfree::LsmfmSolver<dim>::StepResult r;
      {
        dealii::TimerOutput::Scope timer(ctx.timer(), "lsmfm");
        try {
          apply_conditions(*solver, t);
          r = solver->solve_step();
        } catch (NumericalFailure& f) {
          f.set_step(step, t);
          throw;
        }
      }
      newton += r.iterations;
      max_newton = std::max(max_newton, r.iterations);
      min_line_search = std::min(min_line_search, r.min_line_search);
      max_yield_violation = std::max(max_yield_violation, r.max_yield_violation);
      set_fallbacks += r.set_fallbacks;
      if (fem) {
        dealii::TimerOutput::Scope timer(ctx.timer(), "fem");
        try {
          fem->solve_quasi_static(t);
        } catch (NumericalFailure& f) {
          f.set_step(step, t);
          throw;
        }
      }
      const auto avg = averages(*solver);
      if (run_.reaction_boundary_id >= 0)
        reaction = boundary_load(tria, mapping, *solver).norm();
      ctx.history().add({{"time", t},
                         {"stretch", avg[0]},
                         {"flow_stress_MPa", avg[1] / 1e6},
                         {"eff_plastic_strain", avg[2]},
                         {"iterations", double(r.iterations)},
                         {"functional", r.functional},
                         {"plastic_points", double(r.plastic_points)},
                         {"reaction_force", reaction}});
      for (unsigned int i = 0; i < reached.size(); ++i)
        if (!reached[i] && std::abs(avg[0] - run_.reference.stretch[i]) < 1e-6) {
          reached[i] = true;
          at_reference[i] = {{avg[1], avg[2]}};
        }
      ctx.flush_history();
      ctx.progress().update(step, t);
    }
    ctx.progress().finish();

    {
      dealii::TimerOutput::Scope timer(ctx.timer(), "output");
      write_vtu(ctx, *solver);
      if (fem)
        fem->write_output(ctx.output().path().string(), "fem", 0);
    }

    Summary& s = ctx.summary();
    s.set_figure("nodes", nodes_.size(), "-");
    s.set_figure("integration_points", rule.points.size(), "-");
    s.set_figure("unknowns", solver->n_unknowns(), "-");
    s.set_figure("newton_iterations", newton, "iterations");
    s.set_figure("max_newton_iterations_per_step", max_newton, "iterations");
    s.set_figure("min_line_search_factor", min_line_search, "-");
    // The largest violation of the yield condition a load step's plastic set was accepted
    // with (LSMFM/Yield tolerance), over the initial yield stress.
    if (law_.model != "linear_elastic" && law_.yield_stress > 0) {
      s.set_figure("max_yield_violation_relative", max_yield_violation / law_.yield_stress, "-");
      // Load steps whose plastic set cycled and was decided by an iterate-wise solve
      // (max_yield_violation_relative covers the other steps).
      s.set_figure("plastic_set_fallbacks", set_fallbacks, "-");
    }
    double max_spacing = 0;
    for (double h : spacing_)
      max_spacing = std::max(max_spacing, h);
    s.set_figure("node_spacing_m", max_spacing, "m");
    s.set_figure("max_cell_diameter_m", max_cell_diameter(tria), "m");
    unsigned int plastic = 0;
    double max_ep = 0;
    for (unsigned int q = 0; q < solver->n_points(); ++q) {
      plastic += solver->point_plastic_strain(q) > 0;
      max_ep = std::max(max_ep, solver->point_plastic_strain(q));
    }
    s.set_figure("plastic_points", plastic, "-");
    s.set_figure("max_eff_plastic_strain", max_ep, "-");
    if (exact_) {
      exact_->set_time(run_.end_time);
      s.set_figure("displacement_l2_error_relative", exact_error(tria, mapping, *solver).relative(),
                   "-");
    }
    if (run_.reaction_boundary_id >= 0)
      s.set_figure("reaction_force_norm", reaction, dim == 2 ? "N/m" : "N");
    if (fem) {
      s.set_figure("relative_difference_vs_fem", difference_to_fem(*fem, *solver).relative(), "-");
      if (run_.reaction_boundary_id >= 0)
        s.set_figure("fem_reaction_force_norm",
                     fem->reaction_force(run_.reaction_boundary_id).norm(), dim == 2 ? "N/m" : "N");
      s.set_figure("fem_dofs", fem->dof_handler().n_dofs(), "-");
      // The plot when the LSMFM has a plastic zone to show.
      if (run_.plastic_zone_plot && plastic > 0)
        s.set_figure("plastic_zone_png_valid", plastic_zone_plot(ctx, *fem, *solver), "-");
    }
    for (auto& v : at_reference)
      v[0] /= 1e6; // [MPa]
    run_.reference.report(s, at_reference, reached, "LSMFM run");
  }

 private:
  fem::MeshParameters mesh_;
  materials::LawParameters law_;
  typename meshfree::LsmfmSolver<dim>::Material material_;
  typename fem::MechanicsSolver<dim>::Parameters mech_;
  meshfree::LsmfmParameters lsmfm_;
  LsmfmRunParameters run_;
  fem::BoundaryConditions<dim> bcs_;
  std::unique_ptr<dealii::FunctionParser<dim>> exact_;
  std::vector<dealii::Point<dim>> nodes_;
  std::vector<double> spacing_;
  std::vector<BoundaryNode<dim>> boundary_;

  // ∫ σ^h n da over the faces of Reaction boundary id: the force the boundary takes, from the
  // LSMFM's stress unknowns (MLS-evaluated at 3 Gauss points per face direction; the stress
  // field is linear within a support, so the rule is not the limit). In finite strain the
  // current area element by Nanson's formula, n da = J F⁻ᵀ N dA (F of u^h; plane strain:
  // F_zz = 1).
  dealii::Tensor<1, dim> boundary_load(const dealii::Triangulation<dim>& tria,
                                       const dealii::Mapping<dim>& mapping,
                                       const meshfree::LsmfmSolver<dim>& solver) const {
    const dealii::QGauss<dim - 1> quadrature(3);
    dealii::FE_Q<dim> fe(1);
    dealii::FEFaceValues<dim> fv(mapping, fe, quadrature,
                                 dealii::update_quadrature_points | dealii::update_normal_vectors |
                                     dealii::update_JxW_values);
    // Voigt order 11, 22, 33, 12, 23, 13 (LsmfmSolver::Voigt).
    static constexpr unsigned int voigt[3][3] = {{0, 3, 5}, {3, 1, 4}, {5, 4, 2}};
    dealii::Tensor<1, dim> force;
    for (const auto& cell : tria.active_cell_iterators())
      for (unsigned int f = 0; f < cell->n_faces(); ++f) {
        const auto face = cell->face(f);
        if (!face->at_boundary() || face->boundary_id() != static_cast<dealii::types::boundary_id>(
                                                               run_.reaction_boundary_id))
          continue;
        fv.reinit(cell, f);
        for (unsigned int q = 0; q < quadrature.size(); ++q) {
          const auto sigma = solver.stress(fv.quadrature_point(q));
          auto n = fv.normal_vector(q);
          if (lsmfm_.finite_strain()) {
            const auto F = solver.deformation_gradient(fv.quadrature_point(q));
            n = dealii::determinant(F) * (dealii::transpose(dealii::invert(F)) * n);
          }
          for (unsigned int i = 0; i < dim; ++i)
            for (unsigned int j = 0; j < dim; ++j)
              force[i] += sigma[voigt[i][j]] * n[j] * fv.JxW(q);
        }
      }
    return force;
  }

  // Nodes at the vertices; spacing = the longest mesh edge at a vertex (on graded or
  // stretched cells the influence domain must reach the neighbour along the long edge: with
  // the geometric mean cell size instead, h = 1.5 spacings left the perforated plate's
  // elastic solution 1.9 % away from the FEM at 1376 nodes, 0.4 % with this choice);
  // boundary normals per boundary id from the faces around a boundary vertex.
  void make_nodes(const dealii::Triangulation<dim>& tria) {
    std::vector<int> index(tria.n_vertices(), -1);
    std::map<unsigned int, std::map<dealii::types::boundary_id, dealii::Tensor<1, dim>>> normals;
    for (const auto& cell : tria.active_cell_iterators()) {
      for (unsigned int v = 0; v < cell->n_vertices(); ++v) {
        const unsigned int g = cell->vertex_index(v);
        if (index[g] < 0) {
          index[g] = nodes_.size();
          nodes_.push_back(cell->vertex(v));
          spacing_.push_back(0);
        }
      }
      for (unsigned int l = 0; l < cell->n_lines(); ++l) {
        const auto line = cell->line(l);
        const double length = line->vertex(0).distance(line->vertex(1));
        for (unsigned int v = 0; v < 2; ++v) {
          double& h = spacing_[index[line->vertex_index(v)]];
          h = std::max(h, length);
        }
      }
      for (unsigned int f = 0; f < cell->n_faces(); ++f)
        if (cell->face(f)->at_boundary()) {
          const auto n = face_normal<dim>(cell, f);
          const auto id = cell->face(f)->boundary_id();
          for (unsigned int v = 0; v < cell->face(f)->n_vertices(); ++v)
            normals[index[cell->face(f)->vertex_index(v)]][id] += n;
        }
    }
    for (auto& [node, by_id] : normals) {
      BoundaryNode<dim> b{node, {}};
      for (auto& [id, n] : by_id)
        b.normals[id] = n / n.norm();
      boundary_.push_back(b);
    }
    if (run_.node_jitter > 0) {
      std::vector<bool> on_boundary(nodes_.size(), false);
      for (const auto& b : boundary_)
        on_boundary[b.node] = true;
      std::mt19937 gen(run_.seed);
      std::uniform_real_distribution<double> u(-1.0, 1.0);
      for (unsigned int j = 0; j < nodes_.size(); ++j)
        if (!on_boundary[j])
          for (unsigned int d = 0; d < dim; ++d)
            nodes_[j][d] += run_.node_jitter * spacing_[j] * u(gen);
    }
  }

  meshfree::IntegrationRule<dim> integration_rule(const dealii::Triangulation<dim>& tria,
                                                  const dealii::Mapping<dim>& mapping) {
    meshfree::IntegrationRule<dim> rule;
    if (lsmfm_.integration == "background_grid") {
      const dealii::FE_Q<dim> fe(1);
      const dealii::QGauss<dim> quadrature(lsmfm_.grid_points);
      dealii::FEValues<dim> fv(mapping, fe, quadrature,
                               dealii::update_quadrature_points | dealii::update_JxW_values);
      for (const auto& cell : tria.active_cell_iterators()) {
        fv.reinit(cell);
        for (unsigned int q = 0; q < quadrature.size(); ++q) {
          rule.points.push_back(fv.quadrature_point(q));
          rule.weights.push_back(fv.JxW(q));
        }
      }
      return rule;
    }
    dealii::GridTools::Cache<dim> cache(tria, mapping);
    const auto inside = [&](const dealii::Point<dim>& x) {
      try {
        const auto found = dealii::GridTools::find_active_cell_around_point(cache, x);
        return found.first.state() == dealii::IteratorState::valid;
      } catch (...) { // deal.II signals "not found" by an exception in some versions
        return false;
      }
    };
    return meshfree::support_integration<dim>(nodes_, spacing_, lsmfm_.support_ratio,
                                              lsmfm_.integration_ratio, inside,
                                              dealii::GridTools::volume(tria, mapping));
  }

  // Displacement conditions of the Dirichlet slots at time t, traction conditions on every
  // other boundary component (from the Traction and Pressure slots, 0 where none acts).
  void apply_conditions(meshfree::LsmfmSolver<dim>& solver, double t) {
    std::vector<typename meshfree::LsmfmSolver<dim>::DisplacementCondition> uc;
    std::vector<typename meshfree::LsmfmSolver<dim>::TractionCondition> tc;
    for (const auto& b : boundary_) {
      const dealii::Point<dim>& X = nodes_[b.node];
      std::array<bool, dim> held{};
      std::array<double, dim> value{};
      for (const auto& c : bcs_.dirichlet()) {
        bool acts = false;
        for (const auto& [id, n] : b.normals)
          acts = acts || (c.region ? c.region->contains(X) : id == c.boundary_id);
        if (!acts)
          continue;
        c.function->set_time(t);
        for (unsigned int d = 0; d < dim; ++d)
          if (c.mask[d]) {
            held[d] = true;
            value[d] = c.function->value(X, d);
          }
      }
      for (unsigned int d = 0; d < dim; ++d) {
        dealii::Tensor<1, dim> e;
        e[d] = 1;
        if (held[d])
          uc.push_back({b.node, e, value[d]});
      }
      for (const auto& [id, n] : b.normals) {
        dealii::Tensor<1, dim> traction;
        for (const auto& c : bcs_.traction())
          if (c.acts_on(id, X)) {
            c.function->set_time(t);
            for (unsigned int d = 0; d < dim; ++d)
              traction[d] += c.function->value(X, d);
          }
        for (const auto& c : bcs_.pressure())
          if (c.acts_on(id, X)) {
            c.function->set_time(t);
            traction -= c.function->value(X) * n;
          }
        for (unsigned int d = 0; d < dim; ++d)
          if (!held[d]) {
            dealii::Tensor<1, dim> e;
            e[d] = 1;
            tc.push_back({b.node, n, e, traction[d]});
          }
      }
    }
    solver.set_conditions(std::move(uc), std::move(tc));
  }

  // Volume averages over the integration points: stretch F_xx, Cauchy von Mises [Pa],
  // effective plastic strain.
  std::array<double, 3> averages(const meshfree::LsmfmSolver<dim>& solver) const {
    double V = 0, F = 0, vm = 0, ep = 0;
    for (unsigned int q = 0; q < solver.n_points(); ++q) {
      const double w = solver.weight(q) * solver.point_jacobian(q);
      V += w;
      F += w * solver.point_deformation_gradient(q)[0][0];
      vm += w * meshfree::LsmfmSolver<dim>::von_mises(solver.point_stress(q));
      ep += w * solver.point_plastic_strain(q);
    }
    return {{F / V, vm / V, ep / V}};
  }

  static double max_cell_diameter(const dealii::Triangulation<dim>& tria) {
    double h = 0;
    for (const auto& cell : tria.active_cell_iterators())
      h = std::max(h, cell->diameter());
    return h;
  }

  ErrorSums exact_error(const dealii::Triangulation<dim>& tria, const dealii::Mapping<dim>& mapping,
                        const meshfree::LsmfmSolver<dim>& solver) const {
    const dealii::FE_Q<dim> fe(1);
    const dealii::QGauss<dim> quadrature(4);
    dealii::FEValues<dim> fv(mapping, fe, quadrature,
                             dealii::update_quadrature_points | dealii::update_JxW_values);
    ErrorSums sums;
    for (const auto& cell : tria.active_cell_iterators()) {
      fv.reinit(cell);
      for (unsigned int q = 0; q < quadrature.size(); ++q) {
        const auto& X = fv.quadrature_point(q);
        const auto u = solver.displacement(X);
        for (unsigned int d = 0; d < dim; ++d) {
          const double ue = exact_->value(X, d);
          sums.error_squared += fv.JxW(q) * (u[d] - ue) * (u[d] - ue);
          sums.reference_squared += fv.JxW(q) * ue * ue;
        }
      }
    }
    return sums;
  }

  // Eq. (101) with the FEM solution as the reference u_1, on the FEM's Gauss rule.
  ErrorSums difference_to_fem(const fem::MechanicsSolver<dim>& fem,
                              const meshfree::LsmfmSolver<dim>& solver) const {
    const auto& fe = fem.fe();
    const dealii::QGauss<dim> quadrature(fe.degree + 2);
    dealii::FEValues<dim> fv(fem.mapping(), fe, quadrature,
                             dealii::update_values | dealii::update_quadrature_points |
                                 dealii::update_JxW_values);
    std::vector<double> local(fe.n_dofs_per_cell());
    std::vector<dealii::Vector<double>> u_fem(quadrature.size(), dealii::Vector<double>(dim));
    ErrorSums sums;
    for (const auto& cell : fem.dof_handler().active_cell_iterators()) {
      fv.reinit(cell);
      fem.get_cell_values(fem.displacement(), cell, local);
      for (unsigned int q = 0; q < quadrature.size(); ++q) {
        dealii::Tensor<1, dim> uf;
        for (unsigned int i = 0; i < fe.n_dofs_per_cell(); ++i)
          uf[fe.system_to_component_index(i).first] += local[i] * fv.shape_value(i, q);
        const auto u = solver.displacement(fv.quadrature_point(q));
        sums.error_squared += fv.JxW(q) * (u - uf).norm_square();
        sums.reference_squared += fv.JxW(q) * uf.norm_square();
      }
    }
    return sums;
  }

  // Nodes (displacement, stress, von Mises) and integration points (plastic strain, von Mises)
  // as VTU point clouds.
  void write_vtu(RunContext& ctx, const meshfree::LsmfmSolver<dim>& solver) const {
    std::vector<double> volume(nodes_.size());
    for (unsigned int j = 0; j < nodes_.size(); ++j)
      volume[j] = std::pow(spacing_[j], dim);
    auto nodes = meshfree::ParticleSet<dim>::from_points(nodes_, volume);
    auto& vm = nodes.add_scalar_field("von_mises_Pa");
    auto& sxx = nodes.add_scalar_field("stress_xx_Pa");
    auto& syy = nodes.add_scalar_field("stress_yy_Pa");
    auto& sxy = nodes.add_scalar_field("stress_xy_Pa");
    for (unsigned int j = 0; j < nodes_.size(); ++j) {
      nodes.displacement(j) = solver.displacement(nodes_[j]);
      const auto s = solver.stress(nodes_[j]);
      vm[j] = meshfree::LsmfmSolver<dim>::von_mises(s);
      sxx[j] = s[0];
      syy[j] = s[1];
      sxy[j] = s[3];
    }
    meshfree::write_particles_vtu(nodes, (ctx.output().path() / "lsmfm_nodes.vtu").string());
    std::vector<dealii::Point<dim>> pts(solver.n_points());
    std::vector<double> w(solver.n_points());
    for (unsigned int q = 0; q < solver.n_points(); ++q) {
      pts[q] = solver.point(q);
      w[q] = solver.weight(q);
    }
    auto points = meshfree::ParticleSet<dim>::from_points(pts, w);
    auto& ep = points.add_scalar_field("eff_plastic_strain");
    auto& pvm = points.add_scalar_field("von_mises_Pa");
    for (unsigned int q = 0; q < solver.n_points(); ++q) {
      points.displacement(q) = solver.displacement(pts[q]);
      ep[q] = solver.point_plastic_strain(q);
      pvm[q] = meshfree::LsmfmSolver<dim>::von_mises(solver.point_stress(q));
    }
    meshfree::write_particles_vtu(points, (ctx.output().path() / "lsmfm_points.vtu").string());
  }

  // plastic_zone.png: the plastic integration points of the LSMFM beside the plastic
  // quadrature points of the FEM (reference positions, coloured by the effective plastic
  // strain). 1 when a valid PNG was drawn, 0 when not, NaN without gnuplot.
  double plastic_zone_plot(RunContext& ctx, const fem::MechanicsSolver<dim>& fem,
                           const meshfree::LsmfmSolver<dim>& solver) const {
    std::ostringstream ls, fs;
    ls << "# x y eff_plastic_strain (LSMFM integration points)\n";
    for (unsigned int q = 0; q < solver.n_points(); ++q)
      if (solver.point_plastic_strain(q) > 0)
        ls << solver.point(q)[0] << " " << solver.point(q)[1] << " "
           << solver.point_plastic_strain(q) << "\n";
    fs << "# x y eff_plastic_strain (FEM quadrature points)\n";
    fem.refresh_states();
    dealii::FEValues<dim> fv(fem.mapping(), fem.fe(), fem.quadrature(),
                             dealii::update_quadrature_points);
    for (const auto& cell : fem.dof_handler().active_cell_iterators()) {
      fv.reinit(cell);
      const auto data = fem.quadrature_point_data(cell);
      for (unsigned int q = 0; q < data.size(); ++q)
        if (data[q].state.equivalent_plastic_strain > 0)
          fs << fv.quadrature_point(q)[0] << " " << fv.quadrature_point(q)[1] << " "
             << data[q].state.equivalent_plastic_strain << "\n";
    }
    ctx.output().write_atomic("plastic_zone_lsmfm.dat", ls.str());
    ctx.output().write_atomic("plastic_zone_fem.dat", fs.str());
    const auto dir = ctx.output().path();
    std::ostringstream gp;
    gp << "set terminal pngcairo size 1400,650 noenhanced\n"
       << "set output '" << (dir / "plastic_zone.png").string() << "'\n"
       << "set multiplot layout 1,2 title 'Plastic zone (effective plastic strain > 0), "
          "reference positions'\n"
       << "set size ratio -1\nset xlabel 'x [m]'\nset ylabel 'y [m]'\n"
       << "set palette rgb 33,13,10\nset cblabel 'effective plastic strain'\n"
       << "set title 'LSMFM (" << lsmfm_.integration << " integration)'\n"
       << "plot '" << (dir / "plastic_zone_lsmfm.dat").string()
       << "' using 1:2:3 with points pt 7 ps 0.5 palette notitle\n"
       << "set title 'FEM Q" << fem.fe().degree << "'\n"
       << "plot '" << (dir / "plastic_zone_fem.dat").string()
       << "' using 1:2:3 with points pt 7 ps 0.5 palette notitle\n"
       << "unset multiplot\n";
    return draw_with_gnuplot(ctx, "plastic_zone", gp.str(), "plastic_zone_*.dat");
  }
};

} // namespace

SPINESIM_REGISTER_SCENARIO(lsmfm, "lsmfm",
                           "quasi-static elasto-plasticity by the least-squares meshfree method "
                           "(Kwon & Youn 2005): nodes from the mesh, support or background "
                           "integration, optional comparison with the FEM (eq. 101).",
                           "mechanics", create_for_dimension<LsmfmScenario>, sections::geometry(),
                           sections::material(), sections::mechanics(),
                           {"LSMFM", meshfree::LsmfmParameters::declare},
                           {"LSMFM run", LsmfmRunParameters::declare})

} // namespace spinesim::applications
