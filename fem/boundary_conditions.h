#ifndef SPINESIM_FEM_BOUNDARY_CONDITIONS_H
#define SPINESIM_FEM_BOUNDARY_CONDITIONS_H

// Mechanical boundary conditions by boundary id, given as expressions in x, y, z (the
// reference position [m]) and t (time [s]).
//
// Parameter grammar (in the subsection the caller entered, usually "Boundary conditions"):
//   subsection Dirichlet k   (k = 1..n_slots)
//     set Boundary id = 2            # -1 leaves the slot unused
//     set Components  = x,y          # letters from {x,y,z}; unlisted components stay free
//     set Values      = 0; 0.01*t    # one expression per listed component, ';'-separated [m]
//   subsection Traction k
//     set Boundary id = 1
//     set Values      = 1e6*t; 0     # dim expressions, ';'-separated: traction vector [Pa]
//   subsection Pressure k
//     set Boundary id = 0
//     set Value       = 1e6          # normal pressure, positive pushes into the body [Pa]
// Tractions and pressures act on the reference configuration (dead loads).

#include <deal.II/base/function.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/types.h>
#include <deal.II/fe/component_mask.h>

#include <memory>
#include <string>
#include <vector>

namespace spinesim::fem {

template <int dim>
class BoundaryConditions {
 public:
  static constexpr unsigned int n_slots = 6;

  struct Parameters {
    struct Dirichlet {
      int boundary_id = -1;
      std::string components, values;
    };
    struct Traction {
      int boundary_id = -1;
      std::string values;
    };
    struct Pressure {
      int boundary_id = -1;
      std::string value;
    };
    std::vector<Dirichlet> dirichlet; // used slots only
    std::vector<Traction> traction;
    std::vector<Pressure> pressure;

    static void declare(dealii::ParameterHandler& prm);
    // Reads and checks (by building the conditions once); InvalidInput names the entry.
    // subsection_path: where the slots live relative to the current subsection (empty: here).
    void parse(const dealii::ParameterHandler& prm,
               const std::vector<std::string>& subsection_path = {});
  };

  struct Dirichlet {
    dealii::types::boundary_id boundary_id;
    dealii::ComponentMask mask;                      // constrained components
    std::shared_ptr<dealii::Function<dim>> function; // dim components [m]
  };
  struct Traction {
    dealii::types::boundary_id boundary_id;
    std::shared_ptr<dealii::Function<dim>> function; // dim components [Pa]
  };
  struct Pressure {
    dealii::types::boundary_id boundary_id;
    std::shared_ptr<dealii::Function<dim>> function; // scalar [Pa]
  };

  // Adds every used slot of the parameters. `where` prefixes parameter paths in errors.
  void add(const Parameters& parameters, const std::string& where = "Boundary conditions");

  // components: comma-separated letters (x,y[,z]); values: one expression per letter,
  // ';'-separated.
  void add_dirichlet(dealii::types::boundary_id id, const std::string& components,
                     const std::string& values, const std::string& where = "Dirichlet");
  void add_dirichlet(dealii::types::boundary_id id, const dealii::ComponentMask& mask,
                     std::shared_ptr<dealii::Function<dim>> function);
  void add_traction(dealii::types::boundary_id id, const std::string& values,
                    const std::string& where = "Traction");
  void add_traction(dealii::types::boundary_id id, std::shared_ptr<dealii::Function<dim>> function);
  void add_pressure(dealii::types::boundary_id id, const std::string& value,
                    const std::string& where = "Pressure");
  void add_pressure(dealii::types::boundary_id id, std::shared_ptr<dealii::Function<dim>> function);
  void clear();

  const std::vector<Dirichlet>& dirichlet() const { return dirichlet_; }
  const std::vector<Traction>& traction() const { return traction_; }
  const std::vector<Pressure>& pressure() const { return pressure_; }

  // Parses "x,y" into a mask; InvalidInput naming `where` for a letter outside x..(dim).
  static dealii::ComponentMask parse_components(const std::string& components,
                                                const std::string& where);

 private:
  std::vector<Dirichlet> dirichlet_;
  std::vector<Traction> traction_;
  std::vector<Pressure> pressure_;
};

} // namespace spinesim::fem

#endif
