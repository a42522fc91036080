#include "fem/boundary_conditions.h"

#include "fem/materials/failure.h"

#include <deal.II/base/function_parser.h>
#include <deal.II/base/utilities.h>

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
void BoundaryConditions<dim>::Parameters::declare(dealii::ParameterHandler& prm) {
  using namespace dealii;
  for (unsigned int k = 1; k <= n_slots; ++k) {
    prm.enter_subsection("Dirichlet " + std::to_string(k));
    prm.declare_entry("Boundary id", "-1", Patterns::Integer(-1, 255),
                      "Boundary id held by this condition, -1 = slot unused [-].");
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
    prm.declare_entry("Values", "0;0;0", Patterns::Anything(),
                      "Traction vector: dim expressions in x,y,z,t, ';'-separated [Pa].");
    prm.leave_subsection();
  }
  for (unsigned int k = 1; k <= n_slots; ++k) {
    prm.enter_subsection("Pressure " + std::to_string(k));
    prm.declare_entry("Boundary id", "-1", Patterns::Integer(-1, 255),
                      "Boundary id loaded by this pressure, -1 = slot unused [-].");
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
  dirichlet.clear();
  traction.clear();
  pressure.clear();
  for (unsigned int k = 1; k <= n_slots; ++k) {
    const auto path = at("Dirichlet " + std::to_string(k));
    Dirichlet d;
    d.boundary_id = prm.get_integer(path, "Boundary id");
    d.components = prm.get(path, "Components");
    d.values = prm.get(path, "Values");
    if (d.boundary_id >= 0)
      dirichlet.push_back(d);
  }
  for (unsigned int k = 1; k <= n_slots; ++k) {
    const auto path = at("Traction " + std::to_string(k));
    Traction t;
    t.boundary_id = prm.get_integer(path, "Boundary id");
    t.values = prm.get(path, "Values");
    if (t.boundary_id >= 0)
      traction.push_back(t);
  }
  for (unsigned int k = 1; k <= n_slots; ++k) {
    const auto path = at("Pressure " + std::to_string(k));
    Pressure p;
    p.boundary_id = prm.get_integer(path, "Boundary id");
    p.value = prm.get(path, "Value");
    if (p.boundary_id >= 0)
      pressure.push_back(p);
  }
  // Build once so that a bad letter or expression is reported at parse time.
  BoundaryConditions<dim> check;
  check.add(*this);
}

template <int dim>
void BoundaryConditions<dim>::add(const Parameters& p, const std::string& where) {
  // Slot numbers are lost in the used-only lists, so errors name the boundary id instead.
  for (const auto& d : p.dirichlet)
    add_dirichlet(d.boundary_id, d.components, d.values,
                  where + "/Dirichlet (Boundary id " + std::to_string(d.boundary_id) + ")");
  for (const auto& t : p.traction)
    add_traction(t.boundary_id, t.values,
                 where + "/Traction (Boundary id " + std::to_string(t.boundary_id) + ")");
  for (const auto& q : p.pressure)
    add_pressure(q.boundary_id, q.value,
                 where + "/Pressure (Boundary id " + std::to_string(q.boundary_id) + ")");
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
  dirichlet_.push_back({id, mask, std::move(function)});
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
  traction_.push_back({id, std::move(function)});
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
  pressure_.push_back({id, std::move(function)});
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
