#ifndef SPINESIM_BASE_EXPRESSION_FUNCTION_H
#define SPINESIM_BASE_EXPRESSION_FUNCTION_H

// The one reader of vector-valued expressions in parameters ("1e-3*x; -2e-4*y*t"): muparser
// expressions in x, y (z in 3-D) and, when time-dependent, t, with the constant pi, one per
// component and ';'-separated. A wrong count or an expression muparser rejects is InvalidInput
// naming the parameter.

#include <deal.II/base/function_parser.h>

#include <memory>
#include <string>

namespace spinesim {

// `n_components` expressions (0: any number, at least one); `unit` is appended to the
// allowed form, e.g. "[m]". The function is evaluated once at the origin, so that an
// expression muparser only rejects on evaluation is found here.
template <int dim>
std::unique_ptr<dealii::FunctionParser<dim>>
parse_expressions(const std::string& text, const std::string& where, unsigned int n_components,
                  bool time_dependent, const std::string& unit);

} // namespace spinesim

#endif
