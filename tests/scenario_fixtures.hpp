// Small scenarios that several tests start the `centridem` program on: each
// runs in seconds on one core. Change one only with every test that uses it
// (grep the name).
#pragma once

namespace centridem::testutil {

// The CI shear box of examples/shear_small.toml (6 x 6 x 3 mm, about 1,000
// grains of 0.4-0.6 mm), one pressure (100 kPa), sheared 0.15 mm: a few
// seconds.
inline constexpr const char* kSmallShearBox = R"(
description = "report test"
[specimen]
gradation = { bins = [{ d_min_m = 0.4e-3, d_max_m = 0.6e-3, volume_fraction = 1.0 }] }
porosity = 0.40
density_kg_m3 = 2633.0
seed = 11
brick = { size_m = [3e-3, 3e-3, 3e-3] }
region = { lo_m = [0.0, 0.0, 0.0], hi_m = [6e-3, 6e-3, 3e-3] }
[specimen.relax]
contact = "scenario"
[contact.ball_ball]
model = "rrlinear"
effective_modulus_Pa = 300e6
stiffness_ratio = 1.5
friction = 0.5
rolling_friction = 0.16
[shear]
box = { length_m = 6e-3, width_m = 6e-3, height_m = 3e-3 }
normal_stresses_Pa = [100e3]
shear_rate_m_per_s = 0.02
max_shear_displacement_m = 0.15e-3
ball_wall = { model = "linear", effective_modulus_Pa = 1e9, stiffness_ratio = 1.5, friction = 0.0 }
record_interval_steps = 500
local_damping = 0.7
threads = 1
)";

// A tiny benched slope (s = 0.015, grains of 0.2-0.3 mm; seconds to run), one
// trial at 20 g that checkpoints every 1,000 steps; cohesionless after the
// cut, so it slides within its 0.03 s.
inline constexpr const char* kTinySlope = R"(
[specimen]
gradation = { bins = [{ d_min_m = 0.2e-3, d_max_m = 0.3e-3, volume_fraction = 1.0 }] }
porosity = 0.5
density_kg_m3 = 2633.0
seed = 3
brick = { size_m = [2.2575e-3, 1.8e-3, 2.7e-3] }

[contact.ball_ball]
model = "arrlinear"
effective_modulus_Pa = 300e6
stiffness_ratio = 1.5
friction = 0.5
rolling_friction = 0.16
attraction_force_N = 1.2e-4

[slope]
name = "tiny"
size_reduction_factor = 0.015
benches = [{ height_m = 0.075, width_m = 0.03 }, { height_m = 0.075 }]
breadth_m = 0.12

[trial]
check_interval_steps = 500
max_time_s = 0.03
after_failure_time_s = 0.004
checkpoint_interval_min = 0
checkpoint_interval_steps = 1000
at_cut = { friction = 0.0, rolling_friction = 0.0, attraction_force_N = 0.0 }
after_cut = { friction = 0.0, rolling_friction = 0.0, attraction_force_N = 0.0 }

[campaign]
g_levels = [20]

[output]
frame_interval_steps = 10000
vtk = false
picture_width_px = 300
)";

} // namespace centridem::testutil
