#include "io/checkpoint.hpp"

#include "base/errors.hpp"
#include "engine/world.hpp"

#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <fmt/format.h>
#include <fstream>
#include <iterator>
#include <type_traits>
#include <unistd.h>

namespace centridem {

std::uint64_t fnv1a(std::string_view data) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : data) h = (h ^ c) * 1099511628211ull;
  return h;
}

namespace {

constexpr char kMagic[8] = {'C', 'D', 'E', 'M', 'C', 'K', 'P', 'T'};

class Writer {
public:
  template <class T> void pod(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    buf_.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  template <class T> void vec(const std::vector<T>& v) {
    pod(static_cast<std::uint64_t>(v.size()));
    if (!v.empty()) buf_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
  void str(const std::string& s) {
    pod(static_cast<std::uint64_t>(s.size()));
    buf_.append(s);
  }
  void props(const ContactProperties& p) { pod(p); }
  std::string& data() { return buf_; }

private:
  std::string buf_;
};

class Reader {
public:
  Reader(const std::string& data, const std::string& path) : d_(data), path_(path) {}
  template <class T> T pod() {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T));
    T v;
    std::memcpy(&v, d_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  template <class T> std::vector<T> vec() {
    const auto n = pod<std::uint64_t>();
    if (n > (d_.size() - pos_) / (sizeof(T) ? sizeof(T) : 1)) fail("array length beyond the file");
    std::vector<T> v(n);
    if (n) std::memcpy(v.data(), d_.data() + pos_, n * sizeof(T));
    pos_ += n * sizeof(T);
    return v;
  }
  std::string str() {
    const auto n = pod<std::uint64_t>();
    need(n);
    std::string s = d_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  bool done() const { return pos_ == d_.size(); }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError("checkpoint", "\"" + path_ + "\"", "unreadable: " + what);
  }

private:
  void need(std::size_t n) const {
    if (n > d_.size() - pos_) fail("truncated content");
  }
  const std::string& d_;
  const std::string& path_;
  std::size_t pos_ = 0;
};

} // namespace

void write_checkpoint(const World& world, const std::string& path,
                      const std::string& procedure_state) {
  // The neighbour-list state goes with the particles, so the World resumed
  // from the file rebuilds exactly the lists this one has: the run is not
  // perturbed, and both go on with identical order, lists and sums.
  Writer w;
  w.pod(world.settings());
  w.pod(world.clock());
  w.pod(world.body_field());
  w.pod(world.periodic());
  w.props(world.ball_ball_defaults());
  const World::HeightGradedDefaults bands = world.ball_ball_defaults_by_height();
  w.pod(bands.z0_m), w.pod(bands.band_height_m), w.vec(bands.per_band);
  const auto& P = world.particles();
  w.vec(P.position), w.vec(P.velocity), w.vec(P.spin), w.vec(P.applied_force);
  w.vec(P.applied_moment), w.vec(P.displacement), w.vec(P.radius), w.vec(P.mass);
  w.vec(P.inertia), w.vec(P.id), w.vec(P.group), w.vec(P.flags);
  w.pod(static_cast<std::uint64_t>(world.walls().size()));
  for (std::size_t k = 0; k < world.walls().size(); ++k) {
    const Wall& wl = world.walls()[k];
    w.str(wl.name);
    w.pod(wl.shape), w.pod(wl.point), w.pod(wl.normal), w.pod(wl.axis_u), w.pod(wl.axis_v);
    w.pod(wl.half_u), w.pod(wl.half_v), w.pod(wl.velocity), w.pod(wl.force);
    w.pod(wl.contact_count);
    w.pod(wl.normal_stiffness_N_per_m);
    w.pod(wl.servo);
    w.props(world.wall_defaults(k));
  }
  w.vec(world.contact_records());
  const World::BuildState b = world.build_state();
  w.pod(static_cast<std::uint8_t>(b.pending ? 1 : 0));
  w.vec(b.positions), w.vec(b.wall_points), w.vec(b.wall_motion), w.pod(b.cutoff_extra_m);
  w.str(procedure_state);

  std::string payload = std::move(w.data());
  std::string file(kMagic, sizeof kMagic);
  auto put = [&](auto v) { file.append(reinterpret_cast<const char*>(&v), sizeof v); };
  put(static_cast<std::uint32_t>(kCheckpointVersion));
  put(static_cast<std::uint64_t>(payload.size()));
  put(fnv1a(payload));
  file += payload;

  const std::string tmp = path + ".tmp";
  {
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) throw std::runtime_error("cannot write checkpoint " + tmp);
    std::size_t off = 0;
    while (off < file.size()) {
      const ssize_t k = ::write(fd, file.data() + off, file.size() - off);
      if (k <= 0) {
        ::close(fd);
        throw std::runtime_error("cannot write checkpoint " + tmp);
      }
      off += static_cast<std::size_t>(k);
    }
    ::fsync(fd);
    ::close(fd);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
    throw std::runtime_error("cannot rename checkpoint " + tmp + " to " + path);
}

LoadedCheckpoint read_checkpoint(World& world, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("checkpoint", "\"" + path + "\"", "cannot be opened");
  const std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t head = sizeof kMagic + 4 + 8 + 8;
  if (file.size() < head || std::memcmp(file.data(), kMagic, sizeof kMagic) != 0)
    throw InputError("checkpoint", "\"" + path + "\"", "not a centridem checkpoint (bad header)");
  std::uint32_t version;
  std::uint64_t length, sum;
  std::memcpy(&version, file.data() + 8, 4);
  std::memcpy(&length, file.data() + 12, 8);
  std::memcpy(&sum, file.data() + 20, 8);
  if (version != kCheckpointVersion && version != 4)
    throw InputError("checkpoint", "\"" + path + "\"",
                     fmt::format("format version {} is not supported (this build reads 4 to {})",
                                 version, kCheckpointVersion));
  if (file.size() - head != length)
    throw InputError("checkpoint", "\"" + path + "\"",
                     fmt::format("truncated or padded: {} payload bytes, header says {}",
                                 file.size() - head, length));
  const std::string payload = file.substr(head);
  if (fnv1a(payload) != sum)
    throw InputError("checkpoint", "\"" + path + "\"", "corrupt: checksum mismatch");

  Reader r(payload, path);
  if (world.particles().size() != 0 || !world.walls().empty())
    throw std::logic_error("read_checkpoint needs an empty World");
  const auto settings = r.pod<WorldSettings>();
  const auto clock = r.pod<World::Clock>();
  const auto field = r.pod<BodyField>();
  const auto periodic = r.pod<PeriodicBox>();
  const auto bb_defaults = r.pod<ContactProperties>();
  World::HeightGradedDefaults bands;
  if (version >= 5) {
    bands.z0_m = r.pod<double>();
    bands.band_height_m = r.pod<double>();
    bands.per_band = r.vec<ContactProperties>();
  }
  world = World(settings);
  world.set_body_field(field);
  if (periodic.any()) world.set_periodic(periodic);
  world.set_ball_ball_defaults(bb_defaults);
  world.set_ball_ball_defaults_by_height(bands);

  ParticleStore P;
  P.position = r.vec<Vec3>(), P.velocity = r.vec<Vec3>(), P.spin = r.vec<Vec3>();
  P.applied_force = r.vec<Vec3>(), P.applied_moment = r.vec<Vec3>(), P.displacement = r.vec<Vec3>();
  P.radius = r.vec<double>(), P.mass = r.vec<double>(), P.inertia = r.vec<double>();
  P.id = r.vec<std::int64_t>(), P.group = r.vec<std::int32_t>(), P.flags = r.vec<std::uint8_t>();
  const std::size_t n = P.position.size();
  for (std::size_t len :
       {P.velocity.size(), P.spin.size(), P.applied_force.size(), P.applied_moment.size(),
        P.displacement.size(), P.radius.size(), P.mass.size(), P.inertia.size(), P.id.size(),
        P.group.size(), P.flags.size()})
    if (len != n) r.fail("particle arrays of different lengths");
  P.force.assign(n, Vec3{});
  P.moment.assign(n, Vec3{});
  world.particles_mut() = std::move(P);
  world.particles_changed();

  const auto nwalls = r.pod<std::uint64_t>();
  for (std::uint64_t k = 0; k < nwalls; ++k) {
    Wall wl;
    wl.name = r.str();
    wl.shape = r.pod<WallShape>(), wl.point = r.pod<Vec3>(), wl.normal = r.pod<Vec3>();
    wl.axis_u = r.pod<Vec3>(), wl.axis_v = r.pod<Vec3>(), wl.half_u = r.pod<double>();
    wl.half_v = r.pod<double>(), wl.velocity = r.pod<Vec3>(), wl.force = r.pod<Vec3>();
    wl.contact_count = r.pod<std::uint32_t>();
    wl.normal_stiffness_N_per_m = r.pod<double>();
    wl.servo = r.pod<WallServo>();
    const auto props = r.pod<ContactProperties>();
    world.add_wall(std::move(wl), props);
  }
  world.restore_contacts(r.vec<ContactRecord>());
  World::BuildState b;
  b.pending = r.pod<std::uint8_t>() != 0;
  b.positions = r.vec<Vec3>(), b.wall_points = r.vec<Vec3>(), b.wall_motion = r.vec<Vec3>();
  b.cutoff_extra_m = r.pod<double>();
  LoadedCheckpoint out;
  out.procedure_state = r.str();
  if (!r.done()) r.fail("trailing bytes");
  world.set_clock(clock);
  try {
    world.restore_build_state(b);
  } catch (const InputError& e) {
    r.fail(e.what());
  }
  return out;
}

} // namespace centridem
