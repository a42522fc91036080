#include "base/expression_function.h"

#include "base/exceptions.h"

#include <deal.II/base/numbers.h>
#include <deal.II/base/utilities.h>

namespace spinesim {

template <int dim>
std::unique_ptr<dealii::FunctionParser<dim>>
parse_expressions(const std::string& text, const std::string& where, unsigned int n_components,
                  bool time_dependent, const std::string& unit) {
  std::string variables = dim == 2 ? "x,y" : "x,y,z";
  if (time_dependent)
    variables += ",t";
  const auto expressions = dealii::Utilities::split_string_list(text, ';');
  const std::string form = (n_components > 0 ? std::to_string(n_components) + " " : "") +
                           "';'-separated expressions in " + variables + " " + unit;
  if (expressions.empty() || (n_components > 0 && expressions.size() != n_components))
    throw InvalidInput(
        where, "'" + text + "' has " + std::to_string(expressions.size()) + " expressions", form);
  auto f = std::make_unique<dealii::FunctionParser<dim>>(expressions.size());
  try {
    f->initialize(variables, expressions, {{"pi", dealii::numbers::PI}}, time_dependent);
    for (unsigned int c = 0; c < expressions.size(); ++c)
      f->value(dealii::Point<dim>(), c);
  } catch (...) {
    throw InvalidInput(where, "cannot parse '" + text + "'", form);
  }
  return f;
}

template std::unique_ptr<dealii::FunctionParser<2>> parse_expressions<2>(const std::string&,
                                                                         const std::string&,
                                                                         unsigned int, bool,
                                                                         const std::string&);
template std::unique_ptr<dealii::FunctionParser<3>> parse_expressions<3>(const std::string&,
                                                                         const std::string&,
                                                                         unsigned int, bool,
                                                                         const std::string&);

} // namespace spinesim
