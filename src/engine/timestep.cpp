// The timestep: the critical estimate 2 / omega_max over the current contacts
// (with the dashpots' reduction) and the automatic or fixed step chosen from it.
#include "engine/thread_count.hpp"
#include "engine/world.hpp"

#include "base/errors.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>

namespace centridem {

double World::critical_timestep() {
  ensure_built();
  const std::size_t n = p_.size();
  if (n == 0) return std::numeric_limits<double>::infinity();
  const auto& r = p_.radius;
  const auto& m = p_.mass;
  const auto& I = p_.inertia;
  const ContactProperties& def = props_[ball_ball_default_];
  // Per contact, an upper bound of its contribution to the squared highest
  // frequency seen by one particle (column sum of the Gershgorin bound of
  // M^-1 K): normal kn (1/m1 + 1/m2); tangential ks (1/m1 + R1^2/I1 + 1/m2 +
  // R2^2/I2) plus rolling kr (1/I1 + 1/I2). Central differences are stable
  // for dt < 2/omega_max. Walls have infinite mass and inertia.
  auto omega2 = [](const ContactStiffness& k, double m1, double I1, double R1, double m2inv,
                   double I2inv, double R2) {
    const double ln = k.kn * (1.0 / m1 + m2inv);
    const double lt =
        k.ks * (1.0 / m1 + R1 * R1 / I1 + m2inv + R2 * R2 * I2inv) + k.kr * (1.0 / I1 + I2inv);
    return std::max(ln, lt);
  };
  double max_omega2 = 0.0;
  // Each touching ball-ball contact's stiffness is evaluated once, in its
  // row: its share for the first end is summed there, its share for the
  // second end kept by entry and summed below in the incoming order. The
  // sums are those of a pass that visits each particle's row entries, then
  // its incoming entries, then its walls.
  std::vector<double>& end2_share = timestep_scratch_.end2_share;
  std::vector<double>& row_sum = timestep_scratch_.row_sum;
  std::vector<std::uint8_t>& row_any = timestep_scratch_.row_any;
  end2_share.resize(bb_.entries());
  row_sum.resize(n);
  row_any.resize(n);
#pragma omp parallel for schedule(static, 512) num_threads(thread_count(settings_, n))
  for (std::size_t i = 0; i < n; ++i) {
    double w2 = 0.0;
    bool any = false;
    for (std::uint32_t e = bb_.row_offset[i]; e < bb_.row_offset[i + 1]; ++e) {
      const std::uint16_t pr = bb_.properties[e];
      if (pr == kNoContact) continue;
      const std::size_t j = bb_.other[e];
      const double ov = r[i] + r[j] - norm(pair_vector(e, i, j));
      const ContactGeometry g{
          {}, ov, {}, {}, std::min(r[i], r[j]), r[i] + r[j], r[i] * r[j] / (r[i] + r[j]), 0.0};
      const ContactStiffness k = contact_stiffness(props_[pr], g);
      w2 += omega2(k, m[i], I[i], r[i], 1.0 / m[j], 1.0 / I[j], r[j]);
      end2_share[e] = omega2(k, m[j], I[j], r[j], 1.0 / m[i], 1.0 / I[i], r[i]);
      any = true;
    }
    row_sum[i] = w2;
    row_any[i] = any ? 1 : 0;
  }
#pragma omp parallel for schedule(static, 512) num_threads(thread_count(settings_, n))             \
    reduction(max                                                                                  \
              : max_omega2)
  for (std::size_t i = 0; i < n; ++i) {
    bool any = row_any[i] != 0;
    double w2 = row_sum[i];
    for (std::uint32_t k = bb_.incoming_offset[i]; k < bb_.incoming_offset[i + 1]; ++k) {
      const std::uint32_t e = bb_.incoming[k];
      if (bb_.properties[e] == kNoContact) continue;
      w2 += end2_share[e];
      any = true;
    }
    for (std::uint32_t e = bw_.row_offset[i]; e < bw_.row_offset[i + 1]; ++e) {
      if (bw_.properties[e] == kNoContact) continue;
      const ContactGeometry g{{}, 0.0, {}, {}, r[i], r[i], r[i], 0.0};
      w2 +=
          omega2(contact_stiffness(props_[bw_.properties[e]], g), m[i], I[i], r[i], 0.0, 0.0, 0.0);
      any = true;
    }
    if (!any) { // a free particle: as if touching one identical particle, or
                // the stiffest wall, whichever is stiffer (it may land on either)
      const ContactGeometry g{{}, 0.0, {}, {}, r[i], 2 * r[i], 0.5 * r[i], 0.0};
      w2 = omega2(contact_stiffness(def, g), m[i], I[i], r[i], 1.0 / m[i], 1.0 / I[i], r[i]);
      const ContactGeometry gw{{}, 0.0, {}, {}, r[i], r[i], r[i], 0.0};
      for (const Wall& wl : walls_)
        w2 = std::max(w2, omega2(contact_stiffness(props_[wl.properties], gw), m[i], I[i], r[i],
                                 0.0, 0.0, 0.0));
    }
    max_omega2 = std::max(max_omega2, w2);
  }
  // Viscous dashpots lower the stability limit of central differences from
  // 2/omega to (2/omega)(sqrt(1 + beta^2) - beta) (e.g. Belytschko & Hughes,
  // "Computational Methods for Transient Analysis", 1983, ch. 2), with beta
  // the largest dashpot ratio of the property sets in use.
  double beta = 0.0;
  auto consider = [&](std::uint16_t k) {
    beta = std::max({beta, props_[k].dashpot_normal_ratio, props_[k].dashpot_shear_ratio});
  };
  consider(ball_ball_default_);
  for (std::uint16_t k : band_props_) consider(k);
  for (const Wall& wl : walls_) consider(wl.properties);
  for (std::uint16_t k : bb_.properties)
    if (k != kNoContact) consider(k);
  for (std::uint16_t k : bw_.properties)
    if (k != kNoContact) consider(k);
  const double damping_factor = std::sqrt(1.0 + beta * beta) - beta;
  return max_omega2 > 0 ? damping_factor * 2.0 / std::sqrt(max_omega2)
                        : std::numeric_limits<double>::infinity();
}

void World::update_timestep(bool force_estimate) {
  if (settings_.timestep_s > 0) {
    dt_ = settings_.timestep_s;
    // Contacts may stiffen during a run (new contacts, a denser packing):
    // check the fixed timestep on the automatic one's step interval. Not
    // after every rebuild as well (until 2026-12-05): a rebuild does not
    // stiffen a contact, and on the flowing benchmark, which rebuilds every
    // ~90 steps, dropping those checks made the run 1.7 % faster (issue 18,
    // docs/results/bench.md). The first step of a run is checked by cycle()
    // itself.
    if (step_ % settings_.timestep_update_interval == 0) {
      const double crit = critical_timestep();
      if (dt_ > crit)
        throw InstabilityError(fmt::format(
            "fixed timestep {:.4g} s is above the critical timestep {:.4g} s estimated at step "
            "{} (t = {:.6g} s) from the current contacts: they stiffened during the run (more "
            "contacts per particle, or stiffer ones). Likely cause: simulation.timestep_s "
            "chosen for a looser state; use at most {:.4g} s (safety factor {}) or \"auto\"",
            dt_, crit, step_, time_, settings_.timestep_safety_factor * crit,
            settings_.timestep_safety_factor));
    }
    return;
  }
  if (force_estimate || dt_target_ <= 0 || step_ % settings_.timestep_update_interval == 0) {
    const double crit = critical_timestep();
    dt_target_ = std::isfinite(crit) ? settings_.timestep_safety_factor * crit : 1e-6;
  }
  dt_ = dt_ > 0 ? std::min(dt_target_, dt_ * (1.0 + settings_.timestep_growth_limit)) : dt_target_;
}

} // namespace centridem
