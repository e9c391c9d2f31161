#include "procedures/slope_stability.hpp"

#include "base/errors.hpp"
#include "physics/body_field.hpp"
#include "procedures/foundation.hpp"

#include <nlohmann/json.hpp>

namespace centridem {

using json = nlohmann::json;

LeSection slope_section(const SlopeGeometry& geometry) {
  LeSection s;
  for (const SectionPoint& p : geometry.outline()) s.surface.emplace_back(p.x, p.z);
  s.floor_z_m = 0.0;
  return s;
}

double limit_equilibrium_bulk_density(const SlopeScenario& sc, const FoundationResult* f) {
  const LimitEquilibriumSpec& le = sc.limit_equilibrium;
  if (le.bulk_density_kg_m3 > 0) return le.bulk_density_kg_m3;
  if (f && f->prepared) {
    const double n = (f->layer_porosity[0] + f->layer_porosity[1] + f->layer_porosity[2]) / 3.0;
    return sc.specimen.density_kg_m3 * (1.0 - n);
  }
  throw InputError("limit_equilibrium.bulk_density_kg_m3", "0",
                   "the soil's bulk density > 0 [kg/m^3]: without a prepared foundation there "
                   "is no porosity to take it from");
}

SlopeLimitEquilibrium slope_limit_equilibrium(const SlopeScenario& sc,
                                              const SlopeGeometry& geometry, double rho) {
  SlopeLimitEquilibrium r;
  r.cohesion_Pa = sc.limit_equilibrium.cohesion_Pa;
  r.friction_angle_deg = sc.limit_equilibrium.friction_angle_deg;
  r.bulk_density_kg_m3 = rho;
  // The DEM's unit weight at n g is rho n g / s: pass rho / s as the density.
  r.critical = critical_g_level(slope_section(geometry), r.cohesion_Pa, r.friction_angle_deg,
                                rho / geometry.scale());
  return r;
}

LeSearchResult slope_critical_circle(const SlopeScenario& sc, const SlopeGeometry& geometry,
                                     double rho, double g_level) {
  const LeSoil soil{sc.limit_equilibrium.cohesion_Pa, sc.limit_equilibrium.friction_angle_deg,
                    rho * standard_gravity_m_s2 * g_level / geometry.scale()};
  return critical_circle(slope_section(geometry), soil);
}

json to_json(const SlopeLimitEquilibrium& le, const SlopeScenario& sc) {
  const LeSearchResult& c = le.critical.at_critical;
  json arc = json::array();
  for (const auto& [x, z] : c.slip_surface) arc.push_back({x, z});
  return {
      {"method", "Bishop's simplified method, circular slip search (Bishop 1955)"},
      {"cohesion_Pa", le.cohesion_Pa},
      {"friction_angle_deg", le.friction_angle_deg},
      {"bulk_density_kg_m3", le.bulk_density_kg_m3},
      {"source", sc.limit_equilibrium.source},
      {"critical_g", le.critical.g_level},
      {"bracketed", le.critical.bracketed},
      {"factor_of_safety_at_critical_g", c.factor_of_safety},
      {"circle_m", {{"xc", c.circle.xc_m}, {"zc", c.circle.zc_m}, {"radius", c.circle.radius_m}}},
      {"entry_x_m", c.x_entry_m},
      {"exit_x_m", c.x_exit_m},
      {"slip_surface_m", arc}};
}

} // namespace centridem
