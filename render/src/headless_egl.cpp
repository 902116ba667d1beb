#include "pmfrag/render/headless.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkNew.h>

#include <string>

#include "adopt_context.hpp"
#include "glew_shim.hpp"

namespace pmfrag::render {

struct HeadlessWindow::Impl {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  vtkNew<vtkGenericOpenGLRenderWindow> window;
  vtkNew<vtkCallbackCommand> make_current, is_current, supports;
};

namespace {

void make_current_cb(vtkObject*, unsigned long, void* client, void*) {
  auto* m = static_cast<HeadlessWindow::Impl*>(client);
  eglMakeCurrent(m->display, EGL_NO_SURFACE, EGL_NO_SURFACE, m->context);
}
void is_current_cb(vtkObject*, unsigned long, void* client, void* call) {
  auto* m = static_cast<HeadlessWindow::Impl*>(client);
  *static_cast<bool*>(call) = eglGetCurrentContext() == m->context;
}

}  // namespace

HeadlessWindow::HeadlessWindow(int width, int height) : impl_(std::make_unique<Impl>()) {
  auto& m = *impl_;
  auto get_platform_display =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (get_platform_display) m.display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (m.display == EGL_NO_DISPLAY)
    throw NoGraphicsError("no EGL display on Mesa's surfaceless platform (install libegl-mesa0 and libgl1-mesa-dri)");
  EGLint major = 0, minor = 0;
  if (!eglInitialize(m.display, &major, &minor))
    throw NoGraphicsError("EGL initialisation failed (install libegl-mesa0 and libgl1-mesa-dri)");
  const EGLint config_attr[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                EGL_RED_SIZE, 8, EGL_GREEN_SIZE, 8, EGL_BLUE_SIZE, 8, EGL_DEPTH_SIZE, 24, EGL_NONE};
  EGLConfig config;
  EGLint count = 0;
  if (!eglChooseConfig(m.display, config_attr, &config, 1, &count) || count < 1)
    throw NoGraphicsError("no suitable EGL configuration (OpenGL, pbuffer, RGB8, depth 24)");
  eglBindAPI(EGL_OPENGL_API);
  const EGLint context_attr[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 2,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  m.context = eglCreateContext(m.display, config, EGL_NO_CONTEXT, context_attr);
  if (m.context == EGL_NO_CONTEXT) throw NoGraphicsError("cannot create an OpenGL 3.2 core context through EGL");
  if (!eglMakeCurrent(m.display, EGL_NO_SURFACE, EGL_NO_SURFACE, m.context))
    throw NoGraphicsError("cannot make the EGL context current");

  detail::adopt_current_context(
      m.window, {m.make_current, m.is_current, m.supports, make_current_cb, is_current_cb, &m}, width, height);
}

HeadlessWindow::~HeadlessWindow() {
  auto& m = *impl_;
  eglMakeCurrent(m.display, EGL_NO_SURFACE, EGL_NO_SURFACE, m.context);
  m.window->Finalize();
  eglMakeCurrent(m.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(m.display, m.context);
  // The display is process-wide: not terminated while other windows may live.
}

vtkGenericOpenGLRenderWindow* HeadlessWindow::window() const { return impl_->window; }

}  // namespace pmfrag::render
