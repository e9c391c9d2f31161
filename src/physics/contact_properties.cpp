#include "physics/contact_properties.hpp"

#include "base/errors.hpp"

#include <cmath>
#include <fmt/format.h>

namespace centridem {

std::string_view to_string(ContactModel m) {
  switch (m) {
  case ContactModel::linear:
    return "linear";
  case ContactModel::rrlinear:
    return "rrlinear";
  case ContactModel::arrlinear:
    return "arrlinear";
  }
  return "?";
}

ContactModel contact_model_from_string(std::string_view name, const std::string& key) {
  if (name == "linear") return ContactModel::linear;
  if (name == "rrlinear") return ContactModel::rrlinear;
  if (name == "arrlinear") return ContactModel::arrlinear;
  throw InputError(key, fmt::format("\"{}\"", name),
                   "unknown contact model; allowed: \"linear\", \"rrlinear\", \"arrlinear\"");
}

namespace {
void require(bool ok, const std::string& key, double value, const char* allowed) {
  if (!ok || !std::isfinite(value)) throw InputError(key, fmt::format("{:g}", value), allowed);
}
} // namespace

void validate(const ContactProperties& p, const std::string& where) {
  auto k = [&](const char* name) { return where + "." + name; };
  if (p.stiffness_method == StiffnessMethod::deformability) {
    require(p.effective_modulus_Pa > 0, k("effective_modulus_Pa"), p.effective_modulus_Pa,
            "must be > 0 (deformability method: kn = pi r^2 E*/L)");
    require(p.stiffness_ratio > 0, k("stiffness_ratio"), p.stiffness_ratio,
            "must be > 0 (kappa* = kn/ks)");
  } else {
    require(p.normal_stiffness_N_per_m > 0, k("normal_stiffness_N_per_m"),
            p.normal_stiffness_N_per_m, "must be > 0");
    require(p.shear_stiffness_N_per_m >= 0, k("shear_stiffness_N_per_m"), p.shear_stiffness_N_per_m,
            "must be >= 0");
  }
  require(p.friction >= 0, k("friction"), p.friction, "must be >= 0");
  require(p.rolling_friction >= 0, k("rolling_friction"), p.rolling_friction, "must be >= 0");
  require(p.attraction_force_N >= 0, k("attraction_force_N"), p.attraction_force_N, "must be >= 0");
  require(p.attraction_range_m >= 0, k("attraction_range_m"), p.attraction_range_m, "must be >= 0");
  require(p.dashpot_normal_ratio >= 0 && p.dashpot_normal_ratio < 1, k("dashpot_normal_ratio"),
          p.dashpot_normal_ratio, "must be in [0, 1)");
  require(p.dashpot_shear_ratio >= 0 && p.dashpot_shear_ratio < 1, k("dashpot_shear_ratio"),
          p.dashpot_shear_ratio, "must be in [0, 1)");
  require(p.dashpot_mode >= 0 && p.dashpot_mode <= 3, k("dashpot_mode"), p.dashpot_mode,
          "must be 0, 1, 2 or 3 (PFC dp_mode)");
  if (p.model == ContactModel::linear && p.rolling_friction > 0)
    throw InputError(k("rolling_friction"), fmt::format("{:g}", p.rolling_friction),
                     "model \"linear\" has no rolling resistance; use \"rrlinear\" or "
                     "\"arrlinear\", or set it to 0");
  if (p.model != ContactModel::arrlinear && (p.attraction_force_N > 0 || p.attraction_range_m > 0))
    throw InputError(k("attraction_force_N"), fmt::format("{:g}", p.attraction_force_N),
                     "only model \"arrlinear\" has adhesion; use it, or set attraction_force_N "
                     "and attraction_range_m to 0");
}

} // namespace centridem
