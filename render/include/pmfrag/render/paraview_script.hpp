// A ParaView Python script that opens an exported run as pmfrag's frames show it: particles.pvd as shaded
// spheres coloured by fragment_id with pmfrag's palette, under the frames' camera (`pmfrag export
// --paraview-script`).
#pragma once

#include "pmfrag/render/frames.hpp"

#include <string>

namespace pmfrag::render {

/// The script's text. It finds `particles.pvd` beside itself, so the run folder can be moved. `title` is shown
/// at the top of the view (the scene's title and the overrides that ran); `size_px` is the screenshot's side
/// and the aspect the camera was framed for.
std::string paraview_script(const View& view, const std::string& title, int size_px);

}  // namespace pmfrag::render
