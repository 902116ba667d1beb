// The part of a headless window that does not depend on who made the OpenGL context (EGL or OSMesa): VTK's
// generic window asks, through events, to make the context current and whether it is; it then renders into
// its own framebuffer objects.
#pragma once

#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkGenericOpenGLRenderWindow.h>

namespace pmfrag::render::detail {

using ContextFn = void (*)(vtkObject*, unsigned long, void* client, void* call_data);

struct ContextCallbacks {
  vtkCallbackCommand* make_current;  ///< commands owned by the caller's window state
  vtkCallbackCommand* is_current;
  vtkCallbackCommand* supports;
  ContextFn make_current_fn;  ///< makes the context current
  ContextFn is_current_fn;    ///< sets *static_cast<bool*>(call_data)
  void* client;               ///< handed to both functions
};

/// Wires the callbacks into `window` and initializes it from the context current now.
inline void adopt_current_context(vtkGenericOpenGLRenderWindow* window, const ContextCallbacks& cb, int width,
                                  int height) {
  cb.make_current->SetCallback(cb.make_current_fn);
  cb.make_current->SetClientData(cb.client);
  cb.is_current->SetCallback(cb.is_current_fn);
  cb.is_current->SetClientData(cb.client);
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
