#include "vtk_errors.hpp"

#include <mutex>
#include <vector>

#include <fmt/format.h>
#include <vtkLogger.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkOutputWindow.h>

namespace crackvis::render {
namespace {

// The errors of the innermost scope of each thread: sessions render on their
// own threads at once, and each must see only its own.
struct ThreadErrors {
  VtkErrorScope* scope = nullptr;
  std::vector<std::string> errors;
};
thread_local ThreadErrors tErrors;

// The process's output window: errors raised inside a scope are kept for it
// (not printed); everything else goes to the standard window's stderr.
class CapturingOutputWindow : public vtkOutputWindow {
 public:
  static CapturingOutputWindow* New();
  vtkTypeMacro(CapturingOutputWindow, vtkOutputWindow);

  void DisplayErrorText(const char* text) override {
    if (tErrors.scope != nullptr) {
      std::string message = text != nullptr ? text : "";
      while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) {
        message.pop_back();
      }
      tErrors.errors.push_back(std::move(message));
      return;
    }
    vtkOutputWindow::DisplayErrorText(text);
  }
};
vtkStandardNewMacro(CapturingOutputWindow);

void installOnce() {
  static std::once_flag installed;
  std::call_once(installed, [] {
    // VTK's logger would print every error to stderr before the window sees
    // it: the window alone prints what no scope takes.
    vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
    vtkNew<CapturingOutputWindow> window;
    window->SetDisplayModeToAlwaysStdErr();
    vtkOutputWindow::SetInstance(window);
  });
}

}  // namespace

VtkErrorScope::VtkErrorScope() : m_outer(tErrors.scope) {
  installOnce();
  if (m_outer == nullptr) {
    tErrors.errors.clear();
  }
  tErrors.scope = this;
}

VtkErrorScope::~VtkErrorScope() {
  tErrors.scope = m_outer;
}

Status VtkErrorScope::status(std::string_view what) const {
  const auto& errors = tErrors.errors;
  if (errors.empty()) {
    return Status::ok();
  }
  // VTK's text reads "ERROR: In <file>, line <n>\n<class> (<address>): <message>":
  // the class and the message say what failed; the address says nothing.
  std::string first = errors.front();
  if (const auto newline = first.find('\n'); newline != std::string::npos) {
    first = first.substr(newline + 1);
  }
  if (const auto open = first.find(" (0x"); open != std::string::npos) {
    if (const auto close = first.find("): ", open); close != std::string::npos) {
      first.erase(open, close + 1 - open);
    }
  }
  const std::string more =
      errors.size() > 1 ? fmt::format(" (and {} more VTK errors)", errors.size() - 1) : "";
  return internalError(fmt::format("{}: VTK: {}{}", what, first, more));
}

}  // namespace crackvis::render
