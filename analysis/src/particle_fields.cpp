#include "pmfrag/analysis/particle_fields.hpp"

#include <cmath>
#include <stdexcept>

namespace pmfrag::analysis {

const std::vector<std::string>& particle_field_names() {
  static const std::vector<std::string> names{"id",           "phase", "fragment_id",    "fragment_size",
                                              "displacement", "speed", "kinetic_energy", "damage"};
  return names;
}

std::vector<double> particle_field(const std::string& name, const FieldFrame& at) {
  const std::size_t n = at.species.size(), d = static_cast<std::size_t>(at.dim);
  const auto squared = [&](const auto& component, std::size_t i) {
    double s = 0.0;
    for (std::size_t c = 0; c < d; ++c) s += component(i * d + c) * component(i * d + c);
    return s;
  };
  const auto velocity = [&](std::size_t k) { return at.frame.velocity[k]; };
  const auto moved = [&](std::size_t k) { return at.frame.position[k] - at.first.position[k]; };
  const auto fill = [&](auto&& value) {
    std::vector<double> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = value(i);
    return v;
  };
  if (name == "id") return fill([](std::size_t i) { return static_cast<double>(i); });
  if (name == "phase") return fill([&](std::size_t i) { return static_cast<double>(at.species[i]); });
  if (name == "fragment_id") return fill([&](std::size_t i) { return static_cast<double>(at.labels.fragment_id[i]); });
  if (name == "fragment_size") return fill([&](std::size_t i) { return static_cast<double>(at.labels.fragment_size[i]); });
  if (name == "displacement") return fill([&](std::size_t i) { return std::sqrt(squared(moved, i)); });
  if ((name == "speed" || name == "kinetic_energy") && at.frame.velocity.empty())
    throw std::invalid_argument("'" + name + "' needs velocities, and this run's frames hold none (its scene's "
                                "output.fields left them out)");
  if (name == "speed") return fill([&](std::size_t i) { return std::sqrt(squared(velocity, i)); });
  if (name == "kinetic_energy") return fill([&](std::size_t i) { return 0.5 * at.mass[i] * squared(velocity, i); });
  if (name == "damage") return fill([&](std::size_t i) { return at.labels.damage[i]; });
  throw std::invalid_argument("unknown particle field '" + name + "'");
}

}  // namespace pmfrag::analysis
