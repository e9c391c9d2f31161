// `centridem render RUN_DIR [--field displacement|velocity|sliding] [--range LO,HI] [--linear]
// [--section Y,HALF] [--width PX] [--out DIR]`: pictures from a run's saved
// ParaView frames, after the fact (docs/slope.md "Pictures after the run").
//   - a slope trial folder (frames.csv, frames/particles_NNNN.vtu) or a slope
//     campaign folder (each trial in it): the side views of the trial's
//     pictures again, from the frames, with the chosen colour field, range and
//     section; plus checks.png, the slope's checks against the time after the
//     cut (moving mass, its mean speed, the slope's unbalanced-force ratio);
//   - a `run` folder (particles.pvd): side views of its frames, plus
//     measurements.png (ratio, kinetic energy, coordination number against time).
// Pictures go to DIR (default: RUN_DIR/render_<field>); the frames' times are
// the run's own (time after the cut for a trial), as in its log and .pvd.
#pragma once

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace centridem {

struct RenderOptions {
  std::string run_dir;
  std::string out_dir;                // "" = <run>/render_<field>
  std::string field = "displacement"; // displacement | velocity | sliding
  std::vector<double> range;          // {lo, hi} in SI (m, m/s); empty = the default
  bool linear = false;                // linear colour scale instead of log10
  std::vector<double> section;        // {y_mid, half_thickness} [m]; empty = all
  int width_px = 0;                   // 0 = the scenario's picture width (or 1200)
};

int run_render_command(const RenderOptions& options);
CLI::App* add_render_subcommand(CLI::App& app);

} // namespace centridem
