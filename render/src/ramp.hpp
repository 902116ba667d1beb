// The continuous colour ramp of frames and heat maps: perceptual, blue to yellow (viridis-like endpoints
// through five anchors), readable with the common colour-vision deficiencies.
#pragma once

namespace pmfrag::render::detail {
inline constexpr double ramp_anchors[5][3] = {{0.267, 0.005, 0.329}, {0.231, 0.322, 0.545}, {0.129, 0.569, 0.549},
                                              {0.369, 0.788, 0.384}, {0.993, 0.906, 0.144}};
}
