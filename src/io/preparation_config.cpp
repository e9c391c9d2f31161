#include "io/preparation_config.hpp"

#include "io/toml_read.hpp"

#include <fmt/format.h>

namespace centridem {

namespace {
using namespace tomlread;
const Keys kPreparationKeys = {"during_compaction",    "ratio",   "max_steps", "compaction_g_level",
                               "compaction_stress_Pa", "overfill"};
} // namespace

PreparationSpec read_preparation(const toml::table& root, const ContactProperties& material) {
  PreparationSpec p;
  const toml::node* n = root.get("preparation");
  if (!n) return p;
  const std::string P = "preparation";
  const toml::table& t =
      as_table(*n, P, "the specimen preparation (docs/specimens.md \"Preparation\")");
  check_keys(t, P, kPreparationKeys);
  p.enabled = true;
  const toml::node* dc = t.get("during_compaction");
  if (!dc)
    missing(P + ".during_compaction",
            "the contact properties while compacting, a patch over [contact.ball_ball], e.g. "
            "{ friction = 0.2, rolling_friction = 0.0, attraction_force_N = 0.0 }");
  p.during_compaction = read_contact_patch(*dc, P + ".during_compaction");
  validate(apply(p.during_compaction, material), P + ".during_compaction");
  if (auto v = opt_number(
          t, P, "ratio", [](double x) { return x > 0 && x < 1; },
          "mean unbalanced-force ratio that ends compaction and settling: in (0, 1) [-]"))
    p.ratio = *v;
  if (auto v = opt_integer(
          t, P, "max_steps", [](long x) { return x > 0; }, "a step limit > 0 (each phase)"))
    p.max_steps = *v;
  if (auto v = opt_number(
          t, P, "compaction_g_level", [](double x) { return x > 0 && x <= 1e4; },
          "the g-level n of the foundation's compaction (gravity n g / s): in (0, 10000] [-]"))
    p.compaction_g_level = *v;
  if (auto v = opt_number(
          t, P, "compaction_stress_Pa", [](double x) { return x >= 0 && x <= 1e8; },
          "a top plate's stress on the foundation while compacting: 0 (none) to 1e8 [Pa]"))
    p.compaction_stress_Pa = *v;
  if (auto v = opt_number(
          t, P, "overfill", [](double x) { return x >= 1 && x <= 3; },
          "generated foundation height / design height: in [1, 3] [-]"))
    p.overfill = *v;
  return p;
}

std::string resolved_preparation_toml(const PreparationSpec& p) {
  if (!p.enabled) return {};
  return fmt::format("\n[preparation]\nduring_compaction = {}\nratio = {}\nmax_steps = {}\n"
                     "compaction_g_level = {}\ncompaction_stress_Pa = {}\noverfill = {}\n",
                     inline_patch(p.during_compaction), num(p.ratio), p.max_steps,
                     num(p.compaction_g_level), num(p.compaction_stress_Pa), num(p.overfill));
}

} // namespace centridem
