// The colours of frames and heat maps: a continuous ramp, perceptual, blue to yellow (viridis-like endpoints
// through five anchors), and the categories' palette (fragments, phases: category k takes colour k mod 8);
// both readable with the common colour-vision deficiencies.
#pragma once

namespace pmfrag::render::detail {
inline constexpr double ramp_anchors[5][3] = {{0.267, 0.005, 0.329}, {0.231, 0.322, 0.545}, {0.129, 0.569, 0.549},
                                              {0.369, 0.788, 0.384}, {0.993, 0.906, 0.144}};
// Okabe-Ito.
inline constexpr double category_palette[8][3] = {{0.902, 0.624, 0.000}, {0.337, 0.706, 0.914}, {0.000, 0.620, 0.451},
                                                  {0.941, 0.894, 0.259}, {0.000, 0.447, 0.698}, {0.835, 0.369, 0.000},
                                                  {0.800, 0.475, 0.655}, {0.600, 0.600, 0.600}};
/// Particles in no category (targets held in place).
inline constexpr double no_category[3] = {0.88, 0.88, 0.88};
}
