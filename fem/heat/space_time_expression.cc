#include "fem/heat/space_time_expression.h"

#include "base/exceptions.h"

#include <deal.II/base/exceptions.h>

#include <cmath>
#include <map>

namespace spinesim::fem {

namespace {
void initialise_parser(dealii::FunctionParser<3>& parser, const std::string& expression,
                       const std::string& where) {
  const std::map<std::string, double> constants{{"pi", M_PI}};
  try {
    parser.initialize("x,y,z,t", expression, constants, /*time_dependent=*/true);
    // muparser compiles lazily: one evaluation surfaces syntax errors and unknown names now.
    (void)parser.value(dealii::Point<3>());
  } catch (const std::exception& e) {
    throw InvalidInput(where, "cannot parse the expression '" + expression + "'",
                       "a muparser expression in x, y, z, t and the constant pi, e.g. "
                       "'310 + 5*exp(-t)'");
  }
}
} // namespace

template <int dim>
SpaceTimeExpression<dim>::SpaceTimeExpression(const std::string& expression,
                                              const std::string& where)
    : dealii::Function<dim>(1), expression_(expression) {
  initialise_parser(parser_, expression, where);
}

template <int dim>
void SpaceTimeExpression<dim>::validate(const std::string& expression, const std::string& where) {
  dealii::FunctionParser<3> parser;
  initialise_parser(parser, expression, where);
}

template <int dim>
double SpaceTimeExpression<dim>::value(const dealii::Point<dim>& p, const unsigned int) const {
  dealii::Point<3> p3;
  for (unsigned int d = 0; d < dim; ++d)
    p3[d] = p[d];
  return parser_.value(p3);
}

template <int dim>
void SpaceTimeExpression<dim>::set_time(const double new_time) {
  dealii::Function<dim>::set_time(new_time);
  parser_.set_time(new_time);
}

template <int dim>
void SpaceTimeExpression<dim>::advance_time(const double delta_t) {
  set_time(this->get_time() + delta_t);
}

template class SpaceTimeExpression<2>;
template class SpaceTimeExpression<3>;

} // namespace spinesim::fem
