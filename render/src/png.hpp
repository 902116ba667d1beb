// Grab what a window shows and write it as PNG under a temporary name, then rename (no half-written files).
#pragma once

#include <string>

class vtkRenderWindow;

namespace pmfrag::render {
class PngQueue;
}

namespace pmfrag::render::detail {
/// Writes at once, or, with a queue, hands a copy of the pixels to the queue's thread and returns.
/// `shrink` > 1: the window was drawn at that many times the picture's size, and each shrink x shrink block of
/// pixels is averaged into one (supersampling: fine lattices draw without moire).
void write_window_png(vtkRenderWindow* window, const std::string& png_path, int compression, PngQueue* queue = nullptr,
                      int shrink = 1);
}
