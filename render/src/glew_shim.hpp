// Included by exactly one translation unit per build (headless_egl.cpp or headless_osmesa.cpp), so that the
// interposed symbol is in an object file the executable links.
#pragma once

#include <dlfcn.h>

// Debian's GLEW is built for GLX only: glewInit() loads every entry point and then reports
// GLEW_ERROR_NO_GLX_DISPLAY (4), which VTK treats as fatal. With an EGL or OSMesa context current the entry points are
// fine, so this interposed glewInit reports success for that one code. Must stay in an object file that is
// linked in, with default visibility.
extern "C" __attribute__((visibility("default"))) unsigned int glewInit() {
  using Fn = unsigned int (*)();
  static Fn real = reinterpret_cast<Fn>(dlsym(RTLD_NEXT, "glewInit"));
  if (!real) return 1;
  const unsigned int r = real();
  return r == 4 ? 0 : r;
}
