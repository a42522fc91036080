#ifndef SPINESIM_FEM_BOUNDARY_CONDITIONS_H
#define SPINESIM_FEM_BOUNDARY_CONDITIONS_H

// Mechanical boundary conditions by boundary id or by region (an axis-aligned box), given as
// expressions in x, y, z (the reference position [m]) and t (time [s]).
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
// Instead of a Boundary id every slot may give `set Region = x0,y0[,z0]; x1,y1[,z1]` [m]
// (opposite corners of a box, faces included): a Dirichlet slot then constrains every DoF
// whose support point lies in the box (interior ones too), a traction / pressure slot loads
// every boundary face whose centre lies in the box. A slot names one of the two, not both.
// Tractions and pressures act on the reference configuration (dead loads).

#include <deal.II/base/function.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>
#include <deal.II/base/types.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/component_mask.h>
#include <deal.II/fe/mapping.h>

#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace spinesim::fem {

template <int dim>
class BoundaryConditions {
 public:
  static constexpr unsigned int n_slots = 6;

  // Axis-aligned box [m]; points on its faces count as inside (relative tolerance 1e-9 of
  // the box size, so a flat box "0,0; 0,1" selects the line x = 0).
  struct Region {
    dealii::Point<dim> lower, upper;
    bool contains(const dealii::Point<dim>& p) const;
    // "x0,y0[,z0]; x1,y1[,z1]", corners in any order; InvalidInput naming `where`.
    static Region parse(const std::string& text, const std::string& where);
    std::string to_string() const;
  };

  struct Parameters {
    struct Dirichlet {
      int boundary_id = -1;
      std::string region; // empty: by boundary id
      std::string components, values;
    };
    struct Traction {
      int boundary_id = -1;
      std::string region;
      std::string values;
    };
    struct Pressure {
      int boundary_id = -1;
      std::string region;
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

  // Each condition acts on boundary_id unless `region` is set; a region condition's
  // boundary_id is numbers::invalid_boundary_id (so no query by id matches it).
  struct Dirichlet {
    dealii::types::boundary_id boundary_id;
    dealii::ComponentMask mask;                      // constrained components
    std::shared_ptr<dealii::Function<dim>> function; // dim components [m]
    std::optional<Region> region;
    // Does the condition hold this face of a cell: a boundary face with its id, or (region) a
    // face, boundary or interior, whose vertices all lie in the box (unmapped)?
    template <class FaceIterator>
    bool holds_face(const FaceIterator& face) const {
      if (!region)
        return face->at_boundary() && face->boundary_id() == boundary_id;
      for (const unsigned int v : face->vertex_indices())
        if (!region->contains(face->vertex(v)))
          return false;
      return true;
    }
  };
  struct Traction {
    dealii::types::boundary_id boundary_id;
    std::shared_ptr<dealii::Function<dim>> function; // dim components [Pa]
    std::optional<Region> region;
    // Does the condition load the boundary face with this id and (unmapped) centre?
    bool acts_on(dealii::types::boundary_id id, const dealii::Point<dim>& face_centre) const {
      return region ? region->contains(face_centre) : id == boundary_id;
    }
  };
  struct Pressure {
    dealii::types::boundary_id boundary_id;
    std::shared_ptr<dealii::Function<dim>> function; // scalar [Pa]
    std::optional<Region> region;
    bool acts_on(dealii::types::boundary_id id, const dealii::Point<dim>& face_centre) const {
      return region ? region->contains(face_centre) : id == boundary_id;
    }
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
  // The same by region.
  void add_dirichlet(const Region& region, const std::string& components, const std::string& values,
                     const std::string& where = "Dirichlet");
  void add_dirichlet(const Region& region, const dealii::ComponentMask& mask,
                     std::shared_ptr<dealii::Function<dim>> function);
  void add_traction(const Region& region, const std::string& values,
                    const std::string& where = "Traction");
  void add_pressure(const Region& region, const std::string& value,
                    const std::string& where = "Pressure");
  void clear();

  // Values of `function` (dim components, at its current time) at the DoFs that `condition`
  // constrains, on all locally relevant cells; later calls overwrite earlier entries.
  static void interpolate(const Dirichlet& condition, const dealii::Mapping<dim>& mapping,
                          const dealii::DoFHandler<dim>& dof_handler,
                          const dealii::Function<dim>& function,
                          std::map<dealii::types::global_dof_index, double>& values);

  // The DoFs (locally relevant) that `condition` constrains, in any component of its mask.
  static std::set<dealii::types::global_dof_index>
  held_dofs(const Dirichlet& condition, const dealii::Mapping<dim>& mapping,
            const dealii::DoFHandler<dim>& dof_handler);

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
