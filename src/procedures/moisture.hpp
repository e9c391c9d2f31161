// Moisture-graded adhesion in a slope model ([moisture], docs/slope.md
// "Moisture"; the law of F0 against water content is physics/moisture.hpp):
// the model's height H split into `bands` equal horizontal bands, each with
// one F0 = F0 x attraction_factor(middle of the band / H). The lowest and the
// highest band reach below 0 and above H.
#pragma once

#include "engine/world.hpp"
#include "physics/moisture.hpp"

#include <cstddef>
#include <vector>

namespace centridem {

// The factor on F0 of each band, from the bottom [-].
std::vector<double> band_attraction_factors(const MoistureSpec& moisture);

// Each existing ball-ball contact (by the mean height of its two centres)
// gets `base` with F0 x the factor of its band. Returns the contacts changed.
std::size_t grade_attraction_by_height(World& world, const ContactProperties& base,
                                       const MoistureSpec& moisture, double height_m);

// From now on a ball-ball contact is born with `base`, F0 x the factor of the
// band where it is made (World::set_ball_ball_defaults_by_height): a contact
// made after the cut, low in a slid mass, takes the F0 of where it now is.
void grade_new_contacts_by_height(World& world, const ContactProperties& base,
                                  const MoistureSpec& moisture, double height_m);

} // namespace centridem
