#include "pmfrag/render/headless.hpp"

#include <GL/osmesa.h>
#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkNew.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

// The OSMesa build (-DPMFRAG_GL=osmesa), for machines that have only Mesa's off-screen library.
//
// Debian's VTK reaches OpenGL through a GLX-only GLEW: glewInit() asks glXGetProcAddressARB for every entry
// point. The executable links libOSMesa ahead of VTK (render/CMakeLists.txt), so the plain gl* symbols bind
// to OSMesa's; the two functions below, interposed from the executable, hand GLEW OSMesa's entry points and
// report success for the one error code (4, "no GLX display") that is meaningless without X.
extern "C" __attribute__((visibility("default"))) void (*glXGetProcAddressARB(const unsigned char* name))() {
  return reinterpret_cast<void (*)()>(OSMesaGetProcAddress(reinterpret_cast<const char*>(name)));
}
extern "C" __attribute__((visibility("default"))) void (*glXGetProcAddress(const unsigned char* name))() {
  return glXGetProcAddressARB(name);
}
#include "adopt_context.hpp"
#include "glew_shim.hpp"

namespace pmfrag::render {

struct HeadlessWindow::Impl {
  OSMesaContext context = nullptr;
  int width = 0, height = 0;
  std::vector<std::uint8_t> buffer;  // OSMesa's default framebuffer; VTK draws into its own FBO anyway
  vtkNew<vtkGenericOpenGLRenderWindow> window;
  vtkNew<vtkCallbackCommand> make_current, is_current, supports;
};

namespace {

void make_current_cb(vtkObject*, unsigned long, void* client, void*) {
  auto* m = static_cast<HeadlessWindow::Impl*>(client);
  OSMesaMakeCurrent(m->context, m->buffer.data(), GL_UNSIGNED_BYTE, m->width, m->height);
}
void is_current_cb(vtkObject*, unsigned long, void* client, void* call) {
  auto* m = static_cast<HeadlessWindow::Impl*>(client);
  *static_cast<bool*>(call) = OSMesaGetCurrentContext() == m->context;
}

}  // namespace

HeadlessWindow::HeadlessWindow(int width, int height) : impl_(std::make_unique<Impl>()) {
  auto& m = *impl_;
  // Mesa 22's OSMesa dereferences a null screen when GALLIUM_DRIVER names a driver it lacks: refuse first.
  if (const char* drv = std::getenv("GALLIUM_DRIVER"); drv && *drv && std::strcmp(drv, "llvmpipe") != 0 &&
                                                       std::strcmp(drv, "softpipe") != 0)
    throw NoGraphicsError(std::string("GALLIUM_DRIVER=") + drv +
                          " names no driver OSMesa has (it has the software rasterizers llvmpipe and softpipe)");
  const int attr[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                      OSMESA_CONTEXT_MAJOR_VERSION, 3, OSMESA_CONTEXT_MINOR_VERSION, 2, 0};
  m.context = OSMesaCreateContextAttribs(attr, nullptr);
  if (!m.context) throw NoGraphicsError("OSMesa cannot create an OpenGL 3.2 core context (install libosmesa6)");
  m.width = width;
  m.height = height;
  m.buffer.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4, 0);
  if (!OSMesaMakeCurrent(m.context, m.buffer.data(), GL_UNSIGNED_BYTE, width, height))
    throw NoGraphicsError("cannot make the OSMesa context current");

  detail::adopt_current_context(
      m.window, {m.make_current, m.is_current, m.supports, make_current_cb, is_current_cb, &m}, width, height);
}

HeadlessWindow::~HeadlessWindow() {
  auto& m = *impl_;
  OSMesaMakeCurrent(m.context, m.buffer.data(), GL_UNSIGNED_BYTE, m.width, m.height);
  m.window->Finalize();
  OSMesaDestroyContext(m.context);
}

vtkGenericOpenGLRenderWindow* HeadlessWindow::window() const { return impl_->window; }

}  // namespace pmfrag::render
