// A VTK render window with no display: an OpenGL context on Mesa's surfaceless EGL platform driving a
// vtkGenericOpenGLRenderWindow (Debian's VTK 9.1 is built for X only; see docs/rendering.md).
#pragma once

#include <memory>
#include <stdexcept>

class vtkGenericOpenGLRenderWindow;

namespace pmfrag::render {

struct NoGraphicsError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class HeadlessWindow {
 public:
  /// Throws NoGraphicsError (with what to install) if no EGL/OpenGL driver can be opened.
  HeadlessWindow(int width, int height);
  ~HeadlessWindow();
  HeadlessWindow(const HeadlessWindow&) = delete;
  HeadlessWindow& operator=(const HeadlessWindow&) = delete;
  vtkGenericOpenGLRenderWindow* window() const;

  struct Impl;  // EGL display, context and the VTK window (headless_egl.cpp)

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace pmfrag::render
