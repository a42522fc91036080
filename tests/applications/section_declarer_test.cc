// SectionDeclarer: a shared section is declared once, whether its repeats come through the same
// plain function (recognised without printing) or through another function declaring the
// same entries (compared as text); other entries are a std::logic_error.

#include "applications/framework/scenario.h"

#include <deal.II/base/parameter_handler.h>

#include <gtest/gtest.h>

#include <sstream>
#include <stdexcept>

using spinesim::framework::SectionDeclarer;

namespace {

void declare_length(dealii::ParameterHandler& prm) {
  prm.declare_entry("Length", "1", dealii::Patterns::Double(0), "A length [m].");
}
void declare_length_other_default(dealii::ParameterHandler& prm) {
  prm.declare_entry("Length", "2", dealii::Patterns::Double(0), "A length [m].");
}

int counted_calls = 0;
void declare_length_counted(dealii::ParameterHandler& prm) {
  ++counted_calls;
  declare_length(prm);
}

std::string printed(const dealii::ParameterHandler& prm) {
  std::ostringstream text;
  prm.print_parameters(text, dealii::ParameterHandler::OutputStyle::PRM);
  return text.str();
}

} // namespace

TEST(SectionDeclarer, SamePlainFunctionDeclaresOnce) {
  dealii::ParameterHandler prm, once;
  SectionDeclarer sections(prm);
  sections.declare("Geometry", declare_length);
  sections.declare("Geometry", declare_length);
  once.enter_subsection("Geometry");
  declare_length(once);
  once.leave_subsection();
  EXPECT_EQ(printed(prm), printed(once));
  // A repeat through the same function is recognised without calling it again (no
  // printing of either declaration: that cost every start-up a quarter of its work).
  dealii::ParameterHandler counted;
  SectionDeclarer repeats(counted);
  counted_calls = 0;
  for (int i = 0; i < 5; ++i)
    repeats.declare("Geometry", declare_length_counted);
  EXPECT_EQ(counted_calls, 1);
}

TEST(SectionDeclarer, OtherFunctionWithTheSameEntriesIsAccepted) {
  dealii::ParameterHandler prm;
  SectionDeclarer sections(prm);
  sections.declare("Geometry", declare_length);
  EXPECT_NO_THROW(sections.declare("Geometry", [](dealii::ParameterHandler& p) {
    p.declare_entry("Length", "1", dealii::Patterns::Double(0), "A length [m].");
  }));
}

TEST(SectionDeclarer, OtherEntriesAreAProgrammingError) {
  for (const bool lambda_first : {false, true}) {
    dealii::ParameterHandler prm;
    SectionDeclarer sections(prm);
    if (lambda_first)
      sections.declare("Geometry", [](dealii::ParameterHandler& p) { declare_length(p); });
    else
      sections.declare("Geometry", declare_length);
    EXPECT_THROW(sections.declare("Geometry", declare_length_other_default), std::logic_error);
    // Another section is independent.
    EXPECT_NO_THROW(sections.declare("Material", declare_length_other_default));
  }
}
