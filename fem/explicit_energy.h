#ifndef SPINESIM_FEM_EXPLICIT_ENERGY_H
#define SPINESIM_FEM_EXPLICIT_ENERGY_H

// The energy account of central-difference steps (Belytschko, Liu & Moran, Nonlinear Finite
// Elements, 2000, §6.2.3, the energy balance check), for one rank's unknowns. The works are
// trapezoidal sums over the steps, W(t_n) = Σ_{k<n} ½ (G_k + G_{k+1}) · (u_{k+1} − u_k), for a
// force G that acts on an unknown. Central differences give u_{k+1} − u_k = Δt v_{k+½}, so the
// sum can run without storing G: at the force pass of step n (state t_n, velocities v_{n−½}
// before and v_{n+½} after the update) W(t_n) = S_{n−1} + ½ G_n · Δt v_{n−½}, and the running
// sum S_n = W(t_n) + ½ G_n · Δt v_{n+½}. Every figure refers to t_n, the state of the last
// force pass (one step before the state the step leaves).
//
// Kinetic energy at t_n: K = ½ Σ m v_n², v_n = v_{n−½} + ½ Δt_{n−½} a_n the integer-time
// velocity of the reference above (½ (v_{n−½} + v_{n+½}) at a constant step). For a linear,
// undamped, symmetric system at a constant step the trapezoidal works close exactly with the
// central-difference energy K* = ½ Σ m v_{n−½} v_{n+½} = K − ⅛ Δt² Σ m a², so W_ext − (U + K* +
// D) isolates what the time integration does not explain. Where the step changes (landing on
// output times) that identity holds only to second order in the step.

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace spinesim::fem {

// One trapezoidal work, summed as above.
struct TrapezoidWork {
  double running = 0;       // S_n: to t_n plus the forward half interval [J]
  double at_force_pass = 0; // W(t_n) [J]
  // Sums over the unknowns of ½ G Δt v_{n−½} (back) and ½ G Δt v_{n+½} (forward) for step n.
  void add(double back, double forward) {
    at_force_pass = running + back;
    running = at_force_pass + forward;
  }
};

// This rank's share of the account at the last force pass [J] (2-D plane models: per unit
// thickness, J/m). Signs: works are done on the body; dissipations are positive.
struct ExplicitEnergy {
  double time = 0;            // t_n [s]
  TrapezoidWork external;     // supports (net force on Dirichlet unknowns) and loads
  TrapezoidWork interface;    // done through driven unknowns (the coupling interface)
  TrapezoidWork damping;      // dissipated by mass-proportional damping
  TrapezoidWork internal;     // ∫ f_int · du (paths without a stored-energy formula)
  double kinetic = 0;         // K(t_n) = ½ Σ m v_n²
  double kinetic_central = 0; // K*(t_n) = ½ Σ m v_{n−½} v_{n+½}
  // Stored energy U(t_n): ½ u_nᵀ K u_n on the linear explicit path; NaN where only the
  // internal work is known (nonlinear laws: it also holds the plastic dissipation).
  double strain = std::numeric_limits<double>::quiet_NaN();
  bool valid = false; // a force pass has been accounted

  // The running sums a restart must continue (the energies are recomputed at the next force
  // pass): external, interface, damping and internal work, each (running, at_force_pass).
  static constexpr unsigned int n_works = 8;
  std::vector<double> works() const {
    return {external.running, external.at_force_pass, interface.running, interface.at_force_pass,
            damping.running,  damping.at_force_pass,  internal.running,  internal.at_force_pass};
  }
  void set_works(const std::vector<double>& w) {
    TrapezoidWork* parts[] = {&external, &interface, &damping, &internal};
    for (unsigned int k = 0; k < 4 && 2 * k + 1 < w.size(); ++k) {
      parts[k]->running = w[2 * k];
      parts[k]->at_force_pass = w[2 * k + 1];
    }
  }

  // U(t_n) where known, else the internal work (stored energy plus plastic dissipation).
  double stored_or_internal() const { return std::isnan(strain) ? internal.at_force_pass : strain; }

  // One unknown of mass m with velocities vo = v_{n−½}, vn = v_{n+½} over the step dt with the
  // velocity interval h = ½ (dt_back + dt) (base/dynamic_relaxation.h), the net force
  // F = f_ext − f_int of its model at t_n, the external (load) part f_ext of F and damping
  // a [1/s]; `prescribed` unknowns (Dirichlet, driven) take the support force the motion
  // needs, R = m (vn − vo)/h − F, into `prescribed_back/forward`.
  struct Step {
    double external_back = 0, external_forward = 0;
    double prescribed_back = 0, prescribed_forward = 0;
    double damping_back = 0, damping_forward = 0;
    double kinetic = 0, kinetic_central = 0;
    void add(double m, double vo, double vn, double dt, double h, double F, double f_ext,
             bool prescribed, double a) {
      // The damped update's mean velocity, and the velocity at t_n, v_{n−½} + ½ dt_back a_n
      // (½ (vo + vn) at a constant step, dt_back = 2h − dt).
      const double vbar = 0.5 * (vo + vn), back = 0.5 * dt * vo, forward = 0.5 * dt * vn;
      const double vn_time = vo + (1.0 - 0.5 * dt / h) * (vn - vo);
      kinetic += 0.5 * m * vn_time * vn_time;
      kinetic_central += 0.5 * m * vo * vn;
      external_back += f_ext * back;
      external_forward += f_ext * forward;
      if (prescribed) {
        const double R = m * (vn - vo) / h - F;
        prescribed_back += R * back;
        prescribed_forward += R * forward;
      } else if (a != 0) { // the damping force −a m v̄ dissipates a m v̄ · du
        damping_back += a * m * vbar * back;
        damping_forward += a * m * vbar * forward;
      }
    }
  };
};

// The account over all ranks and the parts of a run (FEM, particles) at the last force pass
// [J] (2-D plane models: J/m).
struct EnergyBalance {
  double time = 0;                   // t_n [s]
  double external_work = 0;          // W_ext: supports and loads, on the body
  double interface_work = 0;         // done on the FEM through its driven (interface) DoFs
  double strain_energy = 0;          // U
  double kinetic_energy = 0;         // K = ½ Σ m v_n²
  double kinetic_energy_central = 0; // K* = ½ Σ m v_{n−½} v_{n+½}
  double fracture_dissipation = 0;   // Σ ΔU_break (particles)
  double damping_dissipation = 0;    // mass-proportional damping
  // E0 = K(0) + U(0), the energy the body starts with (an initial velocity field); the balance
  // is W_ext + E0 + E_conv = U + K + D. 0 for a body that starts at rest and undeformed.
  double initial_energy = 0;
  // Coupled runs with conversion: the U + K the conversions added at the states they happened
  // in (the particles' gain less the FEM's loss; coupling/cell_converter.h). A converted cell's
  // energy leaves the FEM's stored energy (½ uᵀ K u on the linear path; on the internal-work
  // path it stays in the FEM's work) and reappears as the particles' stored energy of the
  // inherited field, which the particle model computes differently.
  double conversion_energy = 0;
  // Coupled runs: what the particle zone took in through its ghosts, U_P + K*_P + D_P −
  // W_ext,P (its own balance's defect). With interface_work it is what the splice made:
  // interface_work + interface_work_particles = −defect_central().
  double interface_work_particles = 0;
  bool valid = false; // every rank has accounted a force pass

  double stored_and_dissipated() const {
    return strain_energy + kinetic_energy + fracture_dissipation + damping_dissipation;
  }
  // W_ext + E0 + E_conv
  double supplied() const { return external_work + initial_energy + conversion_energy; }
  // |W_ext + E0 − (U + K + D)| / max(|W_ext + E0|, |U + K + D|); 0 when both vanish.
  double error_relative() const {
    const double in = supplied(), out = stored_and_dissipated();
    const double scale = std::max(std::abs(in), std::abs(out));
    return scale > 0 ? std::abs(in - out) / scale : 0.0;
  }
  // W_ext + E0 − (U + K* + D): zero to round-off for a linear, symmetric, undamped model at a
  // constant step (to second order where it changes); what remains is energy made or lost
  // other than by the time integration.
  double defect_central() const {
    return supplied() -
           (strain_energy + kinetic_energy_central + fracture_dissipation + damping_dissipation);
  }
};

// Sums the parts of this rank (each ExplicitEnergy, plus this rank's fracture dissipation)
// over the ranks of `comm`. Collective.
EnergyBalance sum_energy(const std::vector<const ExplicitEnergy*>& parts, double fracture,
                         MPI_Comm comm);

} // namespace spinesim::fem

#endif
