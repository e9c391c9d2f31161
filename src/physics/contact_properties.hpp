// Contact properties: what a user states for a contact type (ball-ball, or one
// wall's ball-wall contacts). Mirrors the properties of PFC3D's `linear`,
// `rrlinear` and `arrlinear` contact models (PFC 7 manual, "Contact Models");
// the PFC keyword of each field is given in its comment. All SI.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace centridem {

enum class ContactModel : std::uint8_t {
  linear,    // PFC `linear`: linear spring + Coulomb slip (+ optional dashpots)
  rrlinear,  // PFC `rrlinear`: linear + rolling resistance
  arrlinear, // PFC-style adhesive rolling resistance linear (ARRLM, Gilabert et al. 2007)
};

enum class StiffnessMethod : std::uint8_t {
  deformability, // kn = A E*/L, ks = kn/kappa* (PFC `deform emod kratio`)
  direct,        // kn, ks given (PFC `kn`, `ks`)
};

struct ContactProperties {
  ContactModel model = ContactModel::linear;
  StiffnessMethod stiffness_method = StiffnessMethod::deformability;
  double effective_modulus_Pa = 0.0;     // E*    (PFC `emod`)  [Pa]
  double stiffness_ratio = 1.5;          // kappa* = kn/ks (PFC `kratio`) [-]
  double normal_stiffness_N_per_m = 0.0; // kn  (PFC `kn`, direct method) [N/m]
  double shear_stiffness_N_per_m = 0.0;  // ks  (PFC `ks`, direct method) [N/m]
  double friction = 0.0;                 // mu    (PFC `fric`) [-]
  double rolling_friction = 0.0;         // mu_r  (PFC `rr_fric`) [-]
  double attraction_force_N = 0.0;       // F0, maximum attractive force [N]
  double attraction_range_m = 0.0;       // D0, gap at which attraction vanishes [m]
  double dashpot_normal_ratio = 0.0;     // beta_n (PFC `dp_nratio`) [-]
  double dashpot_shear_ratio = 0.0;      // beta_s (PFC `dp_sratio`) [-]
  // PFC `dp_mode`: 0 full normal + full shear; 1 no-tension normal; 2 shear
  // dashpot off while sliding; 3 both 1 and 2.
  int dashpot_mode = 0;
  // Whether the friction and rolling limits use the net normal force (spring
  // minus attraction) instead of the spring force alone (the default).
  bool limits_use_net_force = false;

  bool operator==(const ContactProperties&) const = default;
};

std::string_view to_string(ContactModel m);
ContactModel contact_model_from_string(std::string_view name, const std::string& key);

// Throws InputError naming `where` (e.g. "contact.ball_ball") when a value is
// out of range or a property is not allowed by the chosen model.
void validate(const ContactProperties& p, const std::string& where);

} // namespace centridem
