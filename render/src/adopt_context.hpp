// The part of a headless window that does not depend on who made the OpenGL context (EGL or OSMesa): VTK's
// generic window asks, through events, to make the context current and whether it is; it then renders into
// its own framebuffer objects.
#pragma once

#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkGenericOpenGLRenderWindow.h>

namespace pmfrag::render::detail {

struct ContextCallbacks {
  vtkCallbackCommand* make_current;  ///< client data and callback set by the caller
  vtkCallbackCommand* is_current;    ///< sets *static_cast<bool*>(call_data)
  vtkCallbackCommand* supports;      ///< answers "supports OpenGL" with true
};

/// Wires the callbacks into `window` and initializes it from the context current now.
inline void adopt_current_context(vtkGenericOpenGLRenderWindow* window, const ContextCallbacks& cb, int width,
                                  int height) {
  cb.supports->SetCallback([](vtkObject*, unsigned long, void*, void* call) { *static_cast<bool*>(call) = true; });
  window->AddObserver(vtkCommand::WindowMakeCurrentEvent, cb.make_current);
  window->AddObserver(vtkCommand::WindowIsCurrentEvent, cb.is_current);
  window->AddObserver(vtkCommand::WindowSupportsOpenGLEvent, cb.supports);
  window->SetMultiSamples(0);  // software rasterization: multisampling would multiply the fragment work
  window->SetSize(width, height);
  window->SetOffScreenRendering(1);
  window->InitializeFromCurrentContext();
  window->SetFrameBlitModeToNoBlit();
}

}  // namespace pmfrag::render::detail
