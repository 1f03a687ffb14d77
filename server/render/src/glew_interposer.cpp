// Debian's VTK is linked against a GLX-only GLEW whose glewInit() returns
// GLEW_ERROR_NO_GLX_DISPLAY (4) under EGL, after it has loaded every core GL
// entry point. This definition, exported by the executable (ENABLE_EXPORTS),
// is found before libGLEW's and maps that one result to GLEW_OK; everything
// else passes through. Compiled into each executable that renders (see
// crackvis_enable_rendering in server/render/CMakeLists.txt).
#include <dlfcn.h>

extern "C" unsigned int glewInit() {
  using GlewInit = unsigned int (*)();
  static const auto real = reinterpret_cast<GlewInit>(dlsym(RTLD_NEXT, "glewInit"));
  constexpr unsigned int kGlewOk = 0;
  constexpr unsigned int kNoGlxDisplay = 4;
  const unsigned int result = real != nullptr ? real() : 1;
  return result == kNoGlxDisplay ? kGlewOk : result;
}
