// Grab what a window shows and write it as PNG under a temporary name, then rename (no half-written files).
#pragma once

#include <string>

class vtkRenderWindow;

namespace pmfrag::render::detail {
void write_window_png(vtkRenderWindow* window, const std::string& png_path, int compression);
}
