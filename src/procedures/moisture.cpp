// Moisture-graded adhesion in a slope model (procedures/moisture.hpp).
#include "procedures/moisture.hpp"

#include <cmath>

namespace centridem {

namespace {

ContactProperties graded(ContactProperties c, double factor) {
  c.attraction_force_N *= factor;
  return c;
}

} // namespace

std::vector<double> band_attraction_factors(const MoistureSpec& moisture) {
  const int nb = moisture.bands;
  std::vector<double> f(static_cast<std::size_t>(nb));
  for (int b = 0; b < nb; ++b) f[b] = attraction_factor(moisture, (b + 0.5) / nb);
  return f;
}

std::size_t grade_attraction_by_height(World& world, const ContactProperties& base,
                                       const MoistureSpec& moisture, double height_m) {
  const std::vector<double> factor = band_attraction_factors(moisture);
  const int nb = moisture.bands;
  const double H = height_m;
  const auto& P = world.particles();
  std::size_t changed = 0;
  // The engine's band rule, so that a contact graded here and one born at the
  // same height later fall in the same band.
  for (int b = 0; b < nb; ++b)
    changed += world.modify_ball_ball_contacts(
        [&](std::size_t i, std::size_t j) {
          const double z = 0.5 * (P.position[i].z + P.position[j].z);
          return World::height_band(z, 0.0, H / nb, nb) == b;
        },
        [&](ContactProperties& c) { c = graded(base, factor[b]); });
  return changed;
}

void grade_new_contacts_by_height(World& world, const ContactProperties& base,
                                  const MoistureSpec& moisture, double height_m) {
  World::HeightGradedDefaults g;
  g.z0_m = 0.0;
  g.band_height_m = height_m / moisture.bands;
  for (double f : band_attraction_factors(moisture)) g.per_band.push_back(graded(base, f));
  world.set_ball_ball_defaults_by_height(g);
}

} // namespace centridem
