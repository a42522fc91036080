#include "fem/heat/heat_parameters.h"

#include "base/exceptions.h"
#include "fem/heat/message_format.h"
#include "fem/heat/space_time_expression.h"

#include <cmath>
#include <set>

namespace spinesim::fem {

using namespace dealii;

namespace {
void require_positive(double v, const std::string& where, const std::string& unit) {
  if (!(v > 0) || !std::isfinite(v))
    throw InvalidInput(where, "value " + format_number(v), "a finite positive number " + unit);
}
} // namespace

template <int dim>
void HeatParameters<dim>::declare(ParameterHandler& prm) {
  prm.declare_entry("Finite element degree", "1", Patterns::Integer(1, 4),
                    "Polynomial degree p of the FE_Q temperature element [-].");
  prm.declare_entry("Theta", "1", Patterns::Double(0.5, 1.0),
                    "Time-integration weight [-]: 1 = backward Euler (first order, robust after "
                    "sudden changes), 0.5 = Crank-Nicolson (second order, may oscillate after a "
                    "sudden change of boundary temperature).");
  prm.declare_entry("Time step", "0.01", Patterns::Double(0.0),
                    "Default time step of the heat solver [s]; the driver may pass its own.");
  prm.declare_entry("Initial temperature", "310.15", Patterns::Anything(),
                    "Initial temperature [K]: a muparser expression in x, y, z [m] (z = 0 in 2-D); "
                    "310.15 K is body temperature.");
  prm.declare_entry("Thermal conductivity", "0.54", Patterns::Double(0.0),
                    "Default thermal conductivity k [W/(m K)]. Cortical bone: 0.3-0.6 reported; "
                    "Davidson & James, Med. Eng. Phys. 22 (2000) 741-747 measured about 0.53-0.58 "
                    "for bovine cortical bone.");
  prm.declare_entry("Density", "1900", Patterns::Double(0.0),
                    "Default density rho [kg/m^3] (cortical bone about 1900, as used in "
                    "bone-drilling models, e.g. Davidson & James, J. Biomech. Eng. 125 (2003)).");
  prm.declare_entry("Specific heat", "1300", Patterns::Double(0.0),
                    "Default specific heat capacity c [J/(kg K)] (cortical bone about 1150-1300; "
                    "same sources as Thermal conductivity).");
  for (unsigned int i = 0; i < n_material_slots; ++i) {
    prm.enter_subsection(slot_name("Material", i));
    prm.declare_entry("Material id", "-1", Patterns::Integer(-1),
                      "Cells with this material id use the values below; -1 = unused slot [-].");
    prm.declare_entry("Thermal conductivity", "0.54", Patterns::Double(0.0),
                      "Thermal conductivity k [W/(m K)].");
    prm.declare_entry("Density", "1900", Patterns::Double(0.0), "Density rho [kg/m^3].");
    prm.declare_entry("Specific heat", "1300", Patterns::Double(0.0),
                      "Specific heat capacity c [J/(kg K)].");
    prm.leave_subsection();
  }

  prm.enter_subsection("Perfusion");
  prm.declare_entry("Blood perfusion rate", "0", Patterns::Double(0.0),
                    "Pennes (1948) perfusion w_b: volume of blood through a unit volume of tissue "
                    "per second [1/s]; the heat sink w_b rho_b c_b (T_a - T). 0 = off; "
                    "cancellous bone about 1e-3 to 1e-2 1/s, cortical bone much less.");
  prm.declare_entry("Blood volumetric heat capacity", "3.8e6", Patterns::Double(0.0),
                    "rho_b c_b of blood [J/(m^3 K)] (1060 kg/m^3 x 3600 J/(kg K)).");
  prm.declare_entry("Arterial temperature", "310.15", Patterns::Double(0.0),
                    "Temperature T_a of the blood entering the tissue [K].");
  prm.leave_subsection();

  prm.enter_subsection("Linear solver");
  prm.declare_entry("Preconditioner", "AMG", Patterns::Selection("AMG|SSOR"),
                    "Preconditioner of the CG solver [-]: AMG (Trilinos ML) or SSOR.");
  prm.declare_entry("Tolerance", "1e-10", Patterns::Double(0.0, 1.0),
                    "CG stops when the residual falls below this fraction of the right-hand "
                    "side norm [-].");
  prm.declare_entry("Maximum iterations", "1000", Patterns::Integer(1),
                    "CG iteration limit; exceeding it is a numerical failure [-].");
  prm.leave_subsection();

  prm.enter_subsection("Sources");
  prm.declare_entry("Volumetric source", "0", Patterns::Anything(),
                    "Heat source q [W/m^3]: a muparser expression in x, y, z [m] and t [s].");
  for (unsigned int i = 0; i < n_moving_source_slots; ++i) {
    prm.enter_subsection(slot_name("Moving source", i));
    prm.declare_entry(
        "Power", "0", Patterns::Double(0.0),
        "Total heat input of the moving Gaussian source (drill bit) [W] ([W/m] of depth "
        "in 2-D); 0 = unused slot. All of it enters the body while at least a "
        "fifth of the Gaussian is inside (centre on the surface is fine).");
    prm.declare_entry("Radius", "0.001", Patterns::Double(0.0),
                      "Gaussian radius r [m]: q ~ exp(-|x-c|^2/r^2).");
    prm.declare_entry("Speed", "0", Patterns::Double(0.0),
                      "Speed of the centre along the path [m/s].");
    prm.declare_entry("Path", "0,0", Patterns::Anything(),
                      "Polyline of the centre [m]: points 'x,y' (2-D) or 'x,y,z' (3-D) separated "
                      "by ';'. The centre stays at the last point once it gets there.");
    prm.declare_entry("Start time", "0", Patterns::Double(),
                      "Time the source switches on and starts moving [s].");
    prm.declare_entry("End time", "-1", Patterns::Double(),
                      "Time the source switches off [s]; negative = never.");
    prm.leave_subsection();
  }
  prm.leave_subsection();

  prm.enter_subsection("Boundary conditions");
  for (unsigned int i = 0; i < n_boundary_slots; ++i) {
    prm.enter_subsection(slot_name("Fixed temperature", i));
    prm.declare_entry("Boundary id", "-1", Patterns::Integer(-1),
                      "Boundary with a prescribed temperature; -1 = unused slot [-].");
    prm.declare_entry("Temperature", "310.15", Patterns::Anything(),
                      "Prescribed temperature [K]: expression in x, y, z [m] and t [s].");
    prm.leave_subsection();
  }
  for (unsigned int i = 0; i < n_boundary_slots; ++i) {
    prm.enter_subsection(slot_name("Heat flux", i));
    prm.declare_entry("Boundary id", "-1", Patterns::Integer(-1),
                      "Boundary with a prescribed heat flux; -1 = unused slot [-].");
    prm.declare_entry("Heat flux", "0", Patterns::Anything(),
                      "Heat flux INTO the body [W/m^2]: expression in x, y, z [m] and t [s].");
    prm.leave_subsection();
  }
  for (unsigned int i = 0; i < n_boundary_slots; ++i) {
    prm.enter_subsection(slot_name("Convection", i));
    prm.declare_entry("Boundary id", "-1", Patterns::Integer(-1),
                      "Boundary losing heat h (T - T_inf); -1 = unused slot [-].");
    prm.declare_entry("Heat transfer coefficient", "10", Patterns::Double(0.0),
                      "Heat transfer coefficient h [W/(m^2 K)].");
    prm.declare_entry("Ambient temperature", "293.15", Patterns::Double(0.0),
                      "Ambient temperature T_inf [K].");
    prm.leave_subsection();
  }
  prm.leave_subsection();
  // Unmentioned boundaries are insulated (zero flux).
}

template <int dim>
void HeatParameters<dim>::parse(ParameterHandler& prm) {
  // Enters subsections (the handler is restored on return), hence not const.
  degree = prm.get_integer("Finite element degree");
  theta = prm.get_double("Theta");
  time_step = prm.get_double("Time step");
  initial_temperature = prm.get("Initial temperature");
  default_material.conductivity = prm.get_double("Thermal conductivity");
  default_material.density = prm.get_double("Density");
  default_material.specific_heat = prm.get_double("Specific heat");
  material_overrides.clear();
  for (unsigned int i = 0; i < n_material_slots; ++i) {
    prm.enter_subsection(slot_name("Material", i));
    MaterialOverride m;
    m.material_id = prm.get_integer("Material id");
    m.material.conductivity = prm.get_double("Thermal conductivity");
    m.material.density = prm.get_double("Density");
    m.material.specific_heat = prm.get_double("Specific heat");
    prm.leave_subsection();
    if (m.material_id >= 0)
      material_overrides.push_back(m);
  }

  prm.enter_subsection("Perfusion");
  perfusion.rate = prm.get_double("Blood perfusion rate");
  perfusion.blood_heat_capacity = prm.get_double("Blood volumetric heat capacity");
  perfusion.arterial_temperature = prm.get_double("Arterial temperature");
  prm.leave_subsection();

  prm.enter_subsection("Linear solver");
  preconditioner = prm.get("Preconditioner");
  solver_tolerance = prm.get_double("Tolerance");
  max_iterations = prm.get_integer("Maximum iterations");
  prm.leave_subsection();

  prm.enter_subsection("Sources");
  volumetric_source = prm.get("Volumetric source");
  moving_sources.clear();
  for (unsigned int i = 0; i < n_moving_source_slots; ++i) {
    prm.enter_subsection(slot_name("Moving source", i));
    MovingSource s;
    s.power = prm.get_double("Power");
    s.radius = prm.get_double("Radius");
    s.speed = prm.get_double("Speed");
    s.path = prm.get("Path");
    s.start_time = prm.get_double("Start time");
    s.end_time = prm.get_double("End time");
    prm.leave_subsection();
    if (s.power > 0)
      moving_sources.push_back(s);
  }
  prm.leave_subsection();

  prm.enter_subsection("Boundary conditions");
  fixed_temperatures.clear();
  heat_fluxes.clear();
  convections.clear();
  for (unsigned int i = 0; i < n_boundary_slots; ++i) {
    prm.enter_subsection(slot_name("Fixed temperature", i));
    FixedTemperature f{static_cast<int>(prm.get_integer("Boundary id")), prm.get("Temperature")};
    prm.leave_subsection();
    if (f.boundary_id >= 0)
      fixed_temperatures.push_back(f);
  }
  for (unsigned int i = 0; i < n_boundary_slots; ++i) {
    prm.enter_subsection(slot_name("Heat flux", i));
    HeatFlux f{static_cast<int>(prm.get_integer("Boundary id")), prm.get("Heat flux")};
    prm.leave_subsection();
    if (f.boundary_id >= 0)
      heat_fluxes.push_back(f);
  }
  for (unsigned int i = 0; i < n_boundary_slots; ++i) {
    prm.enter_subsection(slot_name("Convection", i));
    Convection c{static_cast<int>(prm.get_integer("Boundary id")),
                 prm.get_double("Heat transfer coefficient"),
                 prm.get_double("Ambient temperature")};
    prm.leave_subsection();
    if (c.boundary_id >= 0)
      convections.push_back(c);
  }
  prm.leave_subsection();
  validate();
}

template <int dim>
void HeatParameters<dim>::validate() const {
  if (degree < 1 || degree > 4)
    throw InvalidInput("Finite element degree", "degree " + std::to_string(degree),
                       "an integer from 1 to 4");
  if (!(theta >= 0.5 && theta <= 1.0))
    throw InvalidInput("Theta", "value " + format_number(theta),
                       "0.5 <= Theta <= 1 (the unconditionally stable range)");
  require_positive(time_step, "Time step", "[s]");
  SpaceTimeExpression<dim>::validate(initial_temperature, "Initial temperature");
  require_positive(default_material.conductivity, "Thermal conductivity", "[W/(m K)]");
  require_positive(default_material.density, "Density", "[kg/m^3]");
  require_positive(default_material.specific_heat, "Specific heat", "[J/(kg K)]");
  std::set<int> ids;
  for (unsigned int i = 0; i < material_overrides.size(); ++i) {
    const auto& m = material_overrides[i];
    const std::string where = slot_name("Material", i);
    if (m.material_id < 0 || !ids.insert(m.material_id).second)
      throw InvalidInput(where + "/Material id",
                         "material id " + std::to_string(m.material_id) +
                             (m.material_id < 0 ? " in a used slot" : " given twice"),
                         "each material id >= 0 in at most one slot");
    require_positive(m.material.conductivity, where + "/Thermal conductivity", "[W/(m K)]");
    require_positive(m.material.density, where + "/Density", "[kg/m^3]");
    require_positive(m.material.specific_heat, where + "/Specific heat", "[J/(kg K)]");
  }
  if (!(perfusion.rate >= 0) || !std::isfinite(perfusion.rate))
    throw InvalidInput("Perfusion/Blood perfusion rate", "value " + format_number(perfusion.rate),
                       "w_b >= 0 [1/s]");
  require_positive(perfusion.blood_heat_capacity, "Perfusion/Blood volumetric heat capacity",
                   "[J/(m^3 K)]");
  require_positive(perfusion.arterial_temperature, "Perfusion/Arterial temperature", "[K]");
  if (preconditioner != "AMG" && preconditioner != "SSOR")
    throw InvalidInput("Linear solver/Preconditioner", "'" + preconditioner + "'", "AMG or SSOR");
  if (!(solver_tolerance > 0 && solver_tolerance < 1))
    throw InvalidInput("Linear solver/Tolerance", "value " + format_number(solver_tolerance),
                       "a relative tolerance in (0, 1)");
  if (max_iterations < 1)
    throw InvalidInput("Linear solver/Maximum iterations", "0", "at least 1");

  SpaceTimeExpression<dim>::validate(volumetric_source, "Sources/Volumetric source");
  for (unsigned int i = 0; i < moving_sources.size(); ++i)
    moving_source(i); // constructing the source runs all of its checks

  std::set<int> fixed_ids;
  for (unsigned int i = 0; i < fixed_temperatures.size(); ++i) {
    const std::string where = "Boundary conditions/" + slot_name("Fixed temperature", i);
    const int id = fixed_temperatures[i].boundary_id;
    if (id < 0 || !fixed_ids.insert(id).second)
      throw InvalidInput(where + "/Boundary id",
                         "boundary id " + std::to_string(id) +
                             (id < 0 ? " in a used slot" : " has two fixed temperatures"),
                         "each boundary id >= 0 in at most one Fixed temperature slot");
    SpaceTimeExpression<dim>::validate(fixed_temperatures[i].temperature, where + "/Temperature");
  }
  auto check_not_fixed = [&](int id, const std::string& where) {
    if (id < 0)
      throw InvalidInput(where, "boundary id " + std::to_string(id) + " in a used slot",
                         "a boundary id >= 0");
    if (fixed_ids.count(id))
      throw InvalidInput(where,
                         "boundary id " + std::to_string(id) + " also has a fixed temperature",
                         "a boundary that is not in a Fixed temperature slot");
  };
  for (unsigned int i = 0; i < heat_fluxes.size(); ++i) {
    const std::string where = "Boundary conditions/" + slot_name("Heat flux", i);
    check_not_fixed(heat_fluxes[i].boundary_id, where + "/Boundary id");
    SpaceTimeExpression<dim>::validate(heat_fluxes[i].flux, where + "/Heat flux");
  }
  for (unsigned int i = 0; i < convections.size(); ++i) {
    const std::string where = "Boundary conditions/" + slot_name("Convection", i);
    const auto& c = convections[i];
    check_not_fixed(c.boundary_id, where + "/Boundary id");
    if (!(c.heat_transfer_coefficient >= 0) || !std::isfinite(c.heat_transfer_coefficient))
      throw InvalidInput(where + "/Heat transfer coefficient",
                         "value " + format_number(c.heat_transfer_coefficient),
                         "h >= 0 [W/(m^2 K)]");
    require_positive(c.ambient_temperature, where + "/Ambient temperature", "[K]");
  }
}

template <int dim>
MovingHeatSource<dim> HeatParameters<dim>::moving_source(unsigned int i) const {
  const auto& s = moving_sources[i];
  const std::string where = "Sources/" + slot_name("Moving source", i);
  return MovingHeatSource<dim>(MovingHeatSource<dim>::parse_path(s.path, where + "/Path"), s.speed,
                               s.power, s.radius, s.start_time, s.end_time, where);
}

template struct HeatParameters<2>;
template struct HeatParameters<3>;

} // namespace spinesim::fem
