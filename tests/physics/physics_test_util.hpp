// Shared helpers for the analytical physics tests (tests/physics/). Only
// closed-form expressions of the contact law as documented in
// ../shared/DESIGN.md ("Physics") and src/physics/contact_law.hpp; nothing
// here calls engine internals.
#pragma once

#include "engine/world.hpp"
#include "physics/contact_properties.hpp"

#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <vector>

namespace centridem::phys_test {

inline constexpr double pi = std::numbers::pi;

// Solid sphere (particles.cpp): m = 4/3 pi R^3 rho, I = 2/5 m R^2.
inline double sphere_mass(double R, double rho) {
  return 4.0 / 3.0 * pi * R * R * R * rho;
}
inline double sphere_inertia(double R, double rho) {
  return 0.4 * sphere_mass(R, rho) * R * R;
}

// Deformability method (DESIGN.md): kn = pi r^2 E*/L.
// Ball-ball: r = min(R1,R2), L = R1 + R2. Ball-wall: r = L = R.
inline double kn_ball_ball(double E, double R1, double R2) {
  const double r = std::min(R1, R2);
  return pi * r * r * E / (R1 + R2);
}
inline double kn_ball_wall(double E, double R) {
  return pi * R * E;
}
// Rolling radius R-bar = R1 R2/(R1+R2) (wall: R).
inline double rolling_radius(double R1, double R2) {
  return R1 * R2 / (R1 + R2);
}

// Viscous dashpot of a contact (PFC 7 "Linear Model", dp_nratio / dp_sratio):
// coefficient c = 2 beta sqrt(mc k) [N s/m] with the ratio beta [-], the
// effective mass mc = m1 m2/(m1 + m2) [kg] (ball-wall: m) and the spring
// stiffness k [N/m]; the dashpot force is -c times the relative velocity
// (normal or tangential part) of end 2 [N]. dp_mode: 0 full; 1 the normal
// force (spring + dashpot) never tensile; 2 no shear dashpot while sliding;
// 3 both.
inline double dashpot_coefficient(double beta, double mc, double k) {
  return 2.0 * beta * std::sqrt(mc * k);
}

// Adhesion (arrlinear; Gilabert, Roux & Castellanos 2007, Phys. Rev. E 75,
// 011303, as ../shared/DESIGN.md "Physics" fixes it). With overlap d [m]
// (d < 0 is a gap), F0 [N] and range D0 [m]:
//   attraction A(d) = F0 for d >= 0, F0 (1 + d/D0) for -D0 < d < 0, else 0 [N];
//   its potential U(d) = -integral_{-D0}^{d} A(x) dx, zero beyond the range:
//     d >= 0: -F0 D0/2 - F0 d;  -D0 < d < 0: -F0 (D0 + d)^2/(2 D0) [J]
//   (D0 = 0: -F0 d while overlapping).
inline double attraction_N(double F0, double D0, double overlap_m) {
  if (overlap_m >= 0) return F0;
  if (-overlap_m >= D0) return 0.0;
  return F0 * (1.0 + overlap_m / D0);
}
inline double attraction_potential_J(double F0, double D0, double overlap_m) {
  if (overlap_m >= 0) return -F0 * (0.5 * D0 + overlap_m);
  if (-overlap_m >= D0) return 0.0;
  return -F0 * (D0 + overlap_m) * (D0 + overlap_m) / (2.0 * D0);
}
// An adhesive contact at rest under an external compressive normal load N [N]
// has spring force kn d = N + F0. The friction and rolling limits use the
// spring force (limits_use_net_force = false, the default) or the net force
// N (true): largest tangential force mu (N + F0) or mu N [N]; largest rolling
// moment mu_r Rbar (N + F0) or mu_r Rbar N [N m]. Source: contact_law.hpp
// (PFC 7 "Rolling Resistance Linear Model" limits with the ARRLM attraction).
inline double adhesive_shear_limit_N(double mu, double N, double F0, bool net) {
  return mu * (net ? N : N + F0);
}
inline double adhesive_rolling_limit_N_m(double mu_r, double Rbar, double N, double F0, bool net) {
  return mu_r * Rbar * (net ? N : N + F0);
}

inline ContactProperties props(ContactModel model, double E, double friction,
                               double rolling_friction = 0.0, double kratio = 1.5) {
  ContactProperties p;
  p.model = model;
  p.stiffness_method = StiffnessMethod::deformability;
  p.effective_modulus_Pa = E;
  p.stiffness_ratio = kratio;
  p.friction = friction;
  p.rolling_friction = rolling_friction;
  return p;
}

// Uniform gravity field with acceleration g [m/s^2].
inline BodyField gravity(const Vec3& g) {
  BodyField f;
  f.gravity_m_s2 = g;
  return f;
}

// Index of a particle id, failing loudly if it is gone.
inline std::size_t idx(const World& w, std::int64_t id) {
  const std::optional<std::size_t> i = w.index_of(id);
  if (!i) throw std::runtime_error("particle id not found");
  return *i;
}

// Largest relative difference |a - b| / scale.
inline double rel(const Vec3& a, const Vec3& b, double scale) {
  return norm(a - b) / scale;
}

// A loose packing: n spheres with radii uniform in [r_min, r_max] on a cubic
// lattice of spacing `spacing` (> 2 r_max: no initial overlap), nx by ny
// columns, filled layer by layer from `origin`, ids 1..n, random velocities
// uniform in [-v, v]^3 (fixed seed, deterministic), total momentum removed
// when zero_momentum.
inline void add_lattice(World& w, std::size_t n, std::size_t nx, std::size_t ny, double spacing,
                        double r_min, double r_max, double rho, const Vec3& origin, double v,
                        bool zero_momentum, unsigned seed = 12345) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const std::size_t first = w.particles().size();
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t ix = k % nx, iy = (k / nx) % ny, iz = k / (nx * ny);
    const Vec3 x =
        origin + Vec3{spacing * static_cast<double>(ix), spacing * static_cast<double>(iy),
                      spacing * static_cast<double>(iz)};
    const double r = r_min + (r_max - r_min) * u01(rng);
    w.add_particle(x, r, rho, 0, static_cast<std::int64_t>(first + k + 1));
  }
  auto& P = w.particles_mut();
  Vec3 p{};
  double m = 0;
  for (std::size_t i = first; i < P.size(); ++i) {
    P.velocity[i] = {v * (2 * u01(rng) - 1), v * (2 * u01(rng) - 1), v * (2 * u01(rng) - 1)};
    p += P.mass[i] * P.velocity[i];
    m += P.mass[i];
  }
  if (zero_momentum)
    for (std::size_t i = first; i < P.size(); ++i) P.velocity[i] -= p / m;
}

} // namespace centridem::phys_test
