#include <mutex>
#include <vector>

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <fmt/format.h>

#include <crackvis/render/egl_context.hpp>

namespace crackvis::render {
namespace {

std::string eglErrorText() {
  return fmt::format("EGL error 0x{:04x}", eglGetError());
}

// Surfaceless Mesa first (no device needed), then the first EGL device.
EGLDisplay openDisplay(std::string& platform) {
  auto getPlatformDisplay = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (getPlatformDisplay == nullptr) {
    return EGL_NO_DISPLAY;
  }
  EGLDisplay display =
      getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (display != EGL_NO_DISPLAY && eglInitialize(display, nullptr, nullptr) == EGL_TRUE) {
    platform = "surfaceless";
    return display;
  }
  auto queryDevices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  if (queryDevices == nullptr) {
    return EGL_NO_DISPLAY;
  }
  EGLint count = 0;
  queryDevices(0, nullptr, &count);
  std::vector<EGLDeviceEXT> devices(static_cast<std::size_t>(count));
  if (count > 0 && queryDevices(count, devices.data(), &count) == EGL_TRUE) {
    for (EGLDeviceEXT device : devices) {
      display = getPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, device, nullptr);
      if (display != EGL_NO_DISPLAY && eglInitialize(display, nullptr, nullptr) == EGL_TRUE) {
        platform = "device";
        return display;
      }
    }
  }
  return EGL_NO_DISPLAY;
}

// The EGL display is the process's, initialized once and kept: sessions
// come and go, and eglTerminate (which is not reference-counted) would pull
// the display from under the others and unload the driver only for the next
// session to load it again. Contexts and surfaces are per session.
struct ProcessDisplay {
  std::mutex mutex;
  EGLDisplay display = EGL_NO_DISPLAY;
  std::string platform;
  int contexts = 0;
};
ProcessDisplay& processDisplay() {
  static ProcessDisplay shared;
  return shared;
}

}  // namespace

int EglContext::liveCount() {
  auto& shared = processDisplay();
  std::lock_guard lock(shared.mutex);
  return shared.contexts;
}

Result<std::unique_ptr<EglContext>> EglContext::create(int width, int height) {
  std::unique_ptr<EglContext> egl(new EglContext());
  auto& shared = processDisplay();
  std::unique_lock displayLock(shared.mutex);
  if (shared.display == EGL_NO_DISPLAY) {
    shared.display = openDisplay(shared.platform);
  }
  EGLDisplay display = shared.display;
  const std::string platform = shared.platform;
  if (display == EGL_NO_DISPLAY) {
    return failedPrecondition(fmt::format(
        "no EGL display: neither Mesa's surfaceless platform nor an EGL device works ({}); install "
        "libegl-mesa0 and libgl1-mesa-dri, or the NVIDIA driver's EGL",
        eglErrorText()));
  }
  ++shared.contexts;
  displayLock.unlock();
  egl->m_display = display;
  const EGLint configAttributes[] = {EGL_SURFACE_TYPE,
                                     EGL_PBUFFER_BIT,
                                     EGL_RED_SIZE,
                                     8,
                                     EGL_GREEN_SIZE,
                                     8,
                                     EGL_BLUE_SIZE,
                                     8,
                                     EGL_ALPHA_SIZE,
                                     8,
                                     EGL_DEPTH_SIZE,
                                     24,
                                     EGL_RENDERABLE_TYPE,
                                     EGL_OPENGL_BIT,
                                     EGL_NONE};
  EGLConfig config = nullptr;
  EGLint configs = 0;
  if (eglChooseConfig(display, configAttributes, &config, 1, &configs) != EGL_TRUE || configs < 1) {
    return failedPrecondition(fmt::format(
        "eglChooseConfig: no RGBA8 + depth24 OpenGL pbuffer config ({})", eglErrorText()));
  }
  const EGLint pbufferAttributes[] = {EGL_WIDTH, width, EGL_HEIGHT, height, EGL_NONE};
  egl->m_surface = eglCreatePbufferSurface(display, config, pbufferAttributes);
  if (egl->m_surface == EGL_NO_SURFACE) {
    return failedPrecondition(
        fmt::format("eglCreatePbufferSurface {}x{}: {}", width, height, eglErrorText()));
  }
  if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) {
    return failedPrecondition(fmt::format("eglBindAPI(EGL_OPENGL_API): {}", eglErrorText()));
  }
  const EGLint contextAttributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                      3,
                                      EGL_CONTEXT_MINOR_VERSION,
                                      2,
                                      EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                      EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                      EGL_NONE};
  egl->m_context = eglCreateContext(display, config, EGL_NO_CONTEXT, contextAttributes);
  if (egl->m_context == EGL_NO_CONTEXT) {
    return failedPrecondition(
        fmt::format("eglCreateContext (OpenGL 3.2 core): {}", eglErrorText()));
  }
  CRACKVIS_RETURN_IF_ERROR(egl->makeCurrent());
  egl->m_description = fmt::format("EGL {} ({}, {})", eglQueryString(display, EGL_VERSION),
                                   eglQueryString(display, EGL_VENDOR), platform);
  return egl;
}

Status EglContext::makeCurrent() {
  // The client API is a per-thread setting, and a context may be made on
  // one thread and used on another (a session's renderer is made while its
  // file opens): the releases below then act on desktop OpenGL too.
  if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) {
    return failedPrecondition(fmt::format("eglBindAPI(EGL_OPENGL_API): {}", eglErrorText()));
  }
  if (eglMakeCurrent(m_display, m_surface, m_surface, m_context) != EGL_TRUE) {
    return failedPrecondition(fmt::format("eglMakeCurrent: {}", eglErrorText()));
  }
  return Status::ok();
}

void EglContext::releaseFromThread() {
  eglMakeCurrent(m_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglReleaseThread();
}

EglContext::~EglContext() {
  if (m_display == nullptr) {
    return;
  }
  eglMakeCurrent(m_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  if (m_context != nullptr) {
    eglDestroyContext(m_display, m_context);
  }
  if (m_surface != nullptr) {
    eglDestroySurface(m_display, m_surface);
  }
  eglReleaseThread();
  auto& shared = processDisplay();
  std::lock_guard lock(shared.mutex);
  --shared.contexts;
}

}  // namespace crackvis::render
