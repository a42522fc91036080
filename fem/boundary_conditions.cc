#include "fem/boundary_conditions.h"

#include "base/exceptions.h"
#include "base/list_parsing.h"

#include <deal.II/base/function_parser.h>
#include <deal.II/base/quadrature.h>
#include <deal.II/base/utilities.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/numerics/vector_tools.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace spinesim::fem {

namespace {

std::string variables(int dim) {
  return dim == 2 ? "x,y,t" : "x,y,z,t";
}

std::vector<std::string> split_expressions(const std::string& text) {
  std::vector<std::string> out;
  for (auto& s : dealii::Utilities::split_string_list(text, ';'))
    out.push_back(s);
  return out;
}

template <int dim>
std::shared_ptr<dealii::Function<dim>> make_parser(const std::vector<std::string>& expressions,
                                                   const std::string& where) {
  auto f = std::make_shared<dealii::FunctionParser<dim>>(expressions.size());
  try {
    f->initialize(variables(dim), expressions, {{"pi", dealii::numbers::PI}}, true);
    // muparser may only complain on first evaluation: evaluate once here.
    for (unsigned int c = 0; c < expressions.size(); ++c)
      f->value(dealii::Point<dim>(), c);
  } catch (const std::exception& e) {
    std::string joined;
    for (const auto& s : expressions)
      joined += (joined.empty() ? "" : "; ") + s;
    throw InvalidInput(where, "cannot parse expression '" + joined + "'",
                       "muparser expressions in " + variables(dim) + " and pi");
  }
  return f;
}

} // namespace

template <int dim>
bool BoundaryConditions<dim>::Region::contains(const dealii::Point<dim>& p) const {
  double size = 0;
  for (unsigned int d = 0; d < dim; ++d)
    size = std::max({size, upper[d] - lower[d], std::abs(upper[d]), std::abs(lower[d])});
  const double tol = 1e-9 * size;
  for (unsigned int d = 0; d < dim; ++d)
    if (p[d] < lower[d] - tol || p[d] > upper[d] + tol)
      return false;
  return true;
}

template <int dim>
typename BoundaryConditions<dim>::Region
BoundaryConditions<dim>::Region::parse(const std::string& text, const std::string& where) {
  const std::string allowed =
      dim == 2 ? "two corners 'x0,y0; x1,y1' [m]" : "two corners 'x0,y0,z0; x1,y1,z1' [m]";
  const auto corners = dealii::Utilities::split_string_list(text, ';');
  if (corners.size() != 2)
    throw InvalidInput(where, "'" + text + "' does not give two corners", allowed);
  dealii::Point<dim> c[2];
  for (unsigned int k = 0; k < 2; ++k) {
    const auto v = parse_numbers(corners[k], where, dim, "[m] per corner");
    for (unsigned int d = 0; d < dim; ++d)
      c[k][d] = v[d];
  }
  Region r;
  for (unsigned int d = 0; d < dim; ++d) {
    r.lower[d] = std::min(c[0][d], c[1][d]);
    r.upper[d] = std::max(c[0][d], c[1][d]);
  }
  return r;
}

template <int dim>
std::string BoundaryConditions<dim>::Region::to_string() const {
  std::ostringstream o;
  o << lower[0];
  for (unsigned int d = 1; d < dim; ++d)
    o << "," << lower[d];
  o << "; " << upper[0];
  for (unsigned int d = 1; d < dim; ++d)
    o << "," << upper[d];
  return o.str();
}

template <int dim>
void BoundaryConditions<dim>::Parameters::declare(dealii::ParameterHandler& prm) {
  using namespace dealii;
  for (unsigned int k = 1; k <= n_slots; ++k) {
    prm.enter_subsection("Dirichlet " + std::to_string(k));
    prm.declare_entry("Boundary id", "-1", Patterns::Integer(-1, 255),
                      "Boundary id held by this condition, -1 = slot unused [-].");
    prm.declare_entry("Region", "", Patterns::Anything(),
                      "Instead of a boundary id: box 'x0,y0[,z0]; x1,y1[,z1]'; every DoF whose "
                      "support point lies in it (faces included) is constrained [m].");
    prm.declare_entry("Components", "x,y,z", Patterns::Anything(),
                      "Comma-separated constrained components from {x,y,z}; others stay free [-].");
    prm.declare_entry("Values", "0;0;0", Patterns::Anything(),
                      "One expression in x,y,z,t per listed component, ';'-separated [m].");
    prm.leave_subsection();
  }
  for (unsigned int k = 1; k <= n_slots; ++k) {
    prm.enter_subsection("Traction " + std::to_string(k));
    prm.declare_entry("Boundary id", "-1", Patterns::Integer(-1, 255),
                      "Boundary id loaded by this traction, -1 = slot unused [-].");
    prm.declare_entry("Region", "", Patterns::Anything(),
                      "Instead of a boundary id: box 'x0,y0[,z0]; x1,y1[,z1]'; loads every "
                      "boundary face whose centre lies in it [m].");
    prm.declare_entry("Values", "0;0;0", Patterns::Anything(),
                      "Traction vector: dim expressions in x,y,z,t, ';'-separated [Pa].");
    prm.leave_subsection();
  }
  for (unsigned int k = 1; k <= n_slots; ++k) {
    prm.enter_subsection("Pressure " + std::to_string(k));
    prm.declare_entry("Boundary id", "-1", Patterns::Integer(-1, 255),
                      "Boundary id loaded by this pressure, -1 = slot unused [-].");
    prm.declare_entry("Region", "", Patterns::Anything(),
                      "Instead of a boundary id: box 'x0,y0[,z0]; x1,y1[,z1]'; loads every "
                      "boundary face whose centre lies in it [m].");
    prm.declare_entry(
        "Value", "0", Patterns::Anything(),
        "Normal pressure (positive pushes into the body), expression in x,y,z,t [Pa].");
    prm.leave_subsection();
  }
}

template <int dim>
void BoundaryConditions<dim>::Parameters::parse(const dealii::ParameterHandler& prm,
                                                const std::vector<std::string>& subsection_path) {
  auto at = [&](const std::string& slot) {
    auto path = subsection_path;
    path.push_back(slot);
    return path;
  };
  auto check_slot = [](int id, const std::string& region, const std::vector<std::string>& path) {
    std::string name;
    for (const auto& s : path)
      name += (name.empty() ? "" : "/") + s;
    if (id >= 0 && !region.empty())
      throw InvalidInput(name, "gives both Boundary id and Region",
                         "either a Boundary id >= 0 or a Region (the other left unset)");
    if (!region.empty())
      Region::parse(region, name + "/Region");
  };
  dirichlet.clear();
  traction.clear();
  pressure.clear();
  for (unsigned int k = 1; k <= n_slots; ++k) {
    const auto path = at("Dirichlet " + std::to_string(k));
    Dirichlet d;
    d.boundary_id = prm.get_integer(path, "Boundary id");
    d.region = dealii::Utilities::trim(prm.get(path, "Region"));
    d.components = prm.get(path, "Components");
    d.values = prm.get(path, "Values");
    check_slot(d.boundary_id, d.region, path);
    if (d.boundary_id >= 0 || !d.region.empty())
      dirichlet.push_back(d);
  }
  for (unsigned int k = 1; k <= n_slots; ++k) {
    const auto path = at("Traction " + std::to_string(k));
    Traction t;
    t.boundary_id = prm.get_integer(path, "Boundary id");
    t.region = dealii::Utilities::trim(prm.get(path, "Region"));
    t.values = prm.get(path, "Values");
    check_slot(t.boundary_id, t.region, path);
    if (t.boundary_id >= 0 || !t.region.empty())
      traction.push_back(t);
  }
  for (unsigned int k = 1; k <= n_slots; ++k) {
    const auto path = at("Pressure " + std::to_string(k));
    Pressure p;
    p.boundary_id = prm.get_integer(path, "Boundary id");
    p.region = dealii::Utilities::trim(prm.get(path, "Region"));
    p.value = prm.get(path, "Value");
    check_slot(p.boundary_id, p.region, path);
    if (p.boundary_id >= 0 || !p.region.empty())
      pressure.push_back(p);
  }
  // Build once so that a bad letter or expression is reported at parse time.
  BoundaryConditions<dim> check;
  check.add(*this);
}

template <int dim>
void BoundaryConditions<dim>::add(const Parameters& p, const std::string& where) {
  // Slot numbers are lost in the used-only lists, so errors name the boundary id instead.
  auto name = [&](const std::string& kind, int id, const std::string& region) {
    return where + "/" + kind +
           (region.empty() ? " (Boundary id " + std::to_string(id) + ")"
                           : " (Region " + region + ")");
  };
  for (const auto& d : p.dirichlet) {
    const std::string w = name("Dirichlet", d.boundary_id, d.region);
    if (d.region.empty())
      add_dirichlet(d.boundary_id, d.components, d.values, w);
    else
      add_dirichlet(Region::parse(d.region, w + "/Region"), d.components, d.values, w);
  }
  for (const auto& t : p.traction) {
    const std::string w = name("Traction", t.boundary_id, t.region);
    if (t.region.empty())
      add_traction(t.boundary_id, t.values, w);
    else
      add_traction(Region::parse(t.region, w + "/Region"), t.values, w);
  }
  for (const auto& q : p.pressure) {
    const std::string w = name("Pressure", q.boundary_id, q.region);
    if (q.region.empty())
      add_pressure(q.boundary_id, q.value, w);
    else
      add_pressure(Region::parse(q.region, w + "/Region"), q.value, w);
  }
}

template <int dim>
dealii::ComponentMask BoundaryConditions<dim>::parse_components(const std::string& components,
                                                                const std::string& where) {
  std::vector<bool> mask(dim, false);
  const auto letters = dealii::Utilities::split_string_list(components, ',');
  const std::string allowed =
      dim == 2 ? "comma-separated letters from {x,y}" : "comma-separated letters from {x,y,z}";
  if (letters.empty())
    throw InvalidInput(where + "/Components", "no component given", allowed);
  for (const auto& l : letters) {
    const int c = l == "x" ? 0 : l == "y" ? 1 : l == "z" ? 2 : -1;
    if (c < 0 || c >= dim)
      throw InvalidInput(where + "/Components", "unknown component '" + l + "'", allowed);
    if (mask[c])
      throw InvalidInput(where + "/Components", "component '" + l + "' listed twice", allowed);
    mask[c] = true;
  }
  return dealii::ComponentMask(mask);
}

template <int dim>
void BoundaryConditions<dim>::add_dirichlet(dealii::types::boundary_id id,
                                            const std::string& components,
                                            const std::string& values, const std::string& where) {
  const dealii::ComponentMask mask = parse_components(components, where);
  const auto expr = split_expressions(values);
  if (expr.size() != mask.n_selected_components())
    throw InvalidInput(where + "/Values",
                       std::to_string(expr.size()) + " expressions for " +
                           std::to_string(mask.n_selected_components()) + " components",
                       "one ';'-separated expression per listed component");
  std::vector<std::string> all(dim, "0");
  for (unsigned int c = 0, k = 0; c < dim; ++c)
    if (mask[c])
      all[c] = expr[k++];
  add_dirichlet(id, mask, make_parser<dim>(all, where + "/Values"));
}

template <int dim>
void BoundaryConditions<dim>::add_dirichlet(dealii::types::boundary_id id,
                                            const dealii::ComponentMask& mask,
                                            std::shared_ptr<dealii::Function<dim>> function) {
  if (function->n_components != dim)
    throw InvalidInput("Dirichlet", "function must have dim components", "dim components");
  dirichlet_.push_back({id, mask, std::move(function), std::nullopt});
}

template <int dim>
void BoundaryConditions<dim>::add_traction(dealii::types::boundary_id id, const std::string& values,
                                           const std::string& where) {
  const auto expr = split_expressions(values);
  if (expr.size() != dim)
    throw InvalidInput(where + "/Values",
                       std::to_string(expr.size()) + " expressions for a " + std::to_string(dim) +
                           "-D traction",
                       std::to_string(dim) + " ';'-separated expressions");
  add_traction(id, make_parser<dim>(expr, where + "/Values"));
}

template <int dim>
void BoundaryConditions<dim>::add_traction(dealii::types::boundary_id id,
                                           std::shared_ptr<dealii::Function<dim>> function) {
  if (function->n_components != dim)
    throw InvalidInput("Traction", "function must have dim components", "dim components");
  traction_.push_back({id, std::move(function), std::nullopt});
}

template <int dim>
void BoundaryConditions<dim>::add_pressure(dealii::types::boundary_id id, const std::string& value,
                                           const std::string& where) {
  add_pressure(id, make_parser<dim>({value}, where + "/Value"));
}

template <int dim>
void BoundaryConditions<dim>::add_pressure(dealii::types::boundary_id id,
                                           std::shared_ptr<dealii::Function<dim>> function) {
  if (function->n_components != 1)
    throw InvalidInput("Pressure", "function must be scalar", "one component");
  pressure_.push_back({id, std::move(function), std::nullopt});
}

template <int dim>
void BoundaryConditions<dim>::add_dirichlet(const Region& region, const std::string& components,
                                            const std::string& values, const std::string& where) {
  // Parses and checks like a boundary-id slot; a region condition holds no boundary id, so no
  // query by id (reactions, boundary DoFs, particles of boundary cells) picks it up.
  add_dirichlet(dealii::numbers::invalid_boundary_id, components, values, where);
  dirichlet_.back().region = region;
}

template <int dim>
void BoundaryConditions<dim>::add_dirichlet(const Region& region, const dealii::ComponentMask& mask,
                                            std::shared_ptr<dealii::Function<dim>> function) {
  add_dirichlet(dealii::numbers::invalid_boundary_id, mask, std::move(function));
  dirichlet_.back().region = region;
}

template <int dim>
void BoundaryConditions<dim>::add_traction(const Region& region, const std::string& values,
                                           const std::string& where) {
  add_traction(dealii::numbers::invalid_boundary_id, values, where);
  traction_.back().region = region;
}

template <int dim>
void BoundaryConditions<dim>::add_pressure(const Region& region, const std::string& value,
                                           const std::string& where) {
  add_pressure(dealii::numbers::invalid_boundary_id, value, where);
  pressure_.back().region = region;
}

template <int dim>
std::set<dealii::types::global_dof_index>
BoundaryConditions<dim>::held_dofs(const Dirichlet& condition, const dealii::Mapping<dim>& mapping,
                                   const dealii::DoFHandler<dim>& dof_handler) {
  std::map<dealii::types::global_dof_index, double> values;
  interpolate(condition, mapping, dof_handler, dealii::Functions::ZeroFunction<dim>(dim), values);
  std::set<dealii::types::global_dof_index> dofs;
  for (const auto& [dof, value] : values)
    dofs.insert(dofs.end(), dof);
  return dofs;
}

template <int dim>
void BoundaryConditions<dim>::interpolate(
    const Dirichlet& d, const dealii::Mapping<dim>& mapping,
    const dealii::DoFHandler<dim>& dof_handler, const dealii::Function<dim>& function,
    std::map<dealii::types::global_dof_index, double>& values) {
  using namespace dealii;
  if (!d.region) {
    VectorTools::interpolate_boundary_values(mapping, dof_handler, d.boundary_id, function, values,
                                             d.mask);
    return;
  }
  // Region: test the mapped support point of every DoF of every non-artificial cell, so that
  // ghost DoFs get the same value on every rank that sees them.
  const FiniteElement<dim>& fe = dof_handler.get_fe();
  const Quadrature<dim> support(fe.get_unit_support_points());
  FEValues<dim> fe_values(mapping, fe, support, update_quadrature_points);
  std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
  for (const auto& cell : dof_handler.active_cell_iterators()) {
    if (cell->is_artificial())
      continue;
    // Skip cells far from the box; the pad of half the cell's extent keeps curved cells,
    // whose support points may leave the vertex bounding box, in the test.
    const auto corners = cell->bounding_box().get_boundary_points();
    double extent = 0;
    for (unsigned int k = 0; k < dim; ++k)
      extent = std::max(extent, corners.second[k] - corners.first[k]);
    bool overlaps = true;
    for (unsigned int k = 0; k < dim; ++k)
      overlaps = overlaps && corners.second[k] + 0.5 * extent >= d.region->lower[k] &&
                 corners.first[k] - 0.5 * extent <= d.region->upper[k];
    if (!overlaps)
      continue;
    fe_values.reinit(cell);
    cell->get_dof_indices(dofs);
    for (unsigned int i = 0; i < dofs.size(); ++i) {
      const unsigned int c = fe.system_to_component_index(i).first;
      if (!d.mask[c])
        continue;
      const Point<dim>& x = fe_values.quadrature_point(i);
      if (d.region->contains(x))
        values[dofs[i]] = function.value(x, c);
    }
  }
}

template <int dim>
void BoundaryConditions<dim>::clear() {
  dirichlet_.clear();
  traction_.clear();
  pressure_.clear();
}

template class BoundaryConditions<2>;
template class BoundaryConditions<3>;

} // namespace spinesim::fem
