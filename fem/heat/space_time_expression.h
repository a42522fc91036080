#ifndef SPINESIM_FEM_HEAT_SPACE_TIME_EXPRESSION_H
#define SPINESIM_FEM_HEAT_SPACE_TIME_EXPRESSION_H

// A scalar expression in x, y, z, t (z = 0 in 2-D) read from an input file. The same
// variable names in 2-D and 3-D keep scene files dimension-independent.

#include <deal.II/base/function.h>
#include <deal.II/base/function_parser.h>

#include <string>

namespace spinesim::fem {

template <int dim>
class SpaceTimeExpression : public dealii::Function<dim> {
 public:
  // Parses `expression`; throws InvalidInput naming `where` if muparser rejects it.
  // Constant `pi` is predefined.
  SpaceTimeExpression(const std::string& expression, const std::string& where);

  double value(const dealii::Point<dim>& p, const unsigned int component = 0) const override;
  void set_time(const double new_time) override;
  void advance_time(const double delta_t) override;

  const std::string& expression() const { return expression_; }

  // Checks that `expression` parses, without keeping the parser.
  static void validate(const std::string& expression, const std::string& where);

 private:
  std::string expression_;
  dealii::FunctionParser<3> parser_;
};

} // namespace spinesim::fem

#endif
