// The limit-equilibrium estimate beside the DEM (issue 16; docs/slope.md
// "Limit equilibrium"): Bishop's simplified method with a circular slip search
// (procedures/limit_equilibrium.hpp) on the benched slope's undeformed
// section, with the soil's c and phi from [limit_equilibrium] (the shear box
// run on the slope's own material, F0 / s, at the slope's stresses).
//
// Units: the section is in DEM coordinates (m) and the unit weight is the
// DEM's, rho x n g / s, so the stresses, and the factor of safety, are those
// of the centrifuge model at n g (the scaling of Tao et al. section 3.2).
// Uniform gravity, no pore pressure, plane strain (the chamber's side walls
// carry no shear in this estimate).
#pragma once

#include "procedures/limit_equilibrium.hpp"
#include "procedures/slope_config.hpp"
#include "procedures/slope_geometry.hpp"

#include <nlohmann/json_fwd.hpp>

namespace centridem {

struct FoundationResult;

// The undeformed section: the outline from the back wall to the end, soil
// down to the chamber floor (z = 0) [m, DEM].
LeSection slope_section(const SlopeGeometry& geometry);

// The bulk density the estimate uses: [limit_equilibrium].bulk_density_kg_m3,
// or (0) the particle density x (1 - the mean porosity of the prepared
// foundation's layers) [kg/m^3]. Throws InputError when neither is there.
double limit_equilibrium_bulk_density(const SlopeScenario& sc, const FoundationResult* foundation);

struct SlopeLimitEquilibrium {
  double cohesion_Pa = 0, friction_angle_deg = 0, bulk_density_kg_m3 = 0;
  LeCriticalG critical; // g-level where the least factor of safety is 1, and its circle
};

// The critical g-level (searched between 1 and 1000 g).
SlopeLimitEquilibrium slope_limit_equilibrium(const SlopeScenario& sc,
                                              const SlopeGeometry& geometry,
                                              double bulk_density_kg_m3);

// The critical circle and its factor of safety at g-level n.
LeSearchResult slope_critical_circle(const SlopeScenario& sc, const SlopeGeometry& geometry,
                                     double bulk_density_kg_m3, double g_level);

nlohmann::json to_json(const SlopeLimitEquilibrium& le, const SlopeScenario& sc);

} // namespace centridem
