// An off-screen OpenGL context through EGL, with no X server and no window:
// Mesa's surfaceless platform (llvmpipe on CPU nodes) or, failing that, the
// EGL device platform (NVIDIA GPUs). Every EGL call is checked; failures name
// the call and the EGL error. The context and its surface are released in
// the destructor; the display is the process's, initialized by the first
// context and kept for the next sessions.
#pragma once

#include <memory>
#include <string>

#include <crackvis/common/status.hpp>

namespace crackvis::render {

class EglContext {
 public:
  // A desktop OpenGL 3.2 core context with a pbuffer of width x height.
  static Result<std::unique_ptr<EglContext>> create(int width, int height);
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;
  ~EglContext();

  Status makeCurrent();
  // Leaves the context current on no thread and frees this thread's EGL
  // state: the thread that made a context hands it to another, which then
  // makes it current (a context is current on one thread at a time).
  void releaseFromThread();
  // Contexts alive in this process (a test checks that a closed session
  // leaves none behind).
  static int liveCount();
  // "EGL 1.5 (Mesa Project, surfaceless)" and the like, for start-up logs.
  const std::string& description() const { return m_description; }

 private:
  EglContext() = default;
  void* m_display = nullptr;  // EGLDisplay
  void* m_surface = nullptr;  // EGLSurface
  void* m_context = nullptr;  // EGLContext
  std::string m_description;
};

}  // namespace crackvis::render
