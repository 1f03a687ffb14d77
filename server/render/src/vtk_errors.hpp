// VTK reports its errors (a shader that does not compile, a failing GL call,
// a file it cannot write) as text through vtkOutputWindow and lets the call
// return normally. A VtkErrorScope collects the errors raised on its thread
// while it lives, so that the call that caused them returns them as a Status
// (as lastHdf5Error() does for HDF5) instead of OK with a line on stderr.
// Errors outside any scope, and warnings, are printed as before.
#pragma once

#include <string>
#include <string_view>

#include <crackvis/common/status.hpp>

namespace crackvis::render {

class VtkErrorScope {
 public:
  VtkErrorScope();
  ~VtkErrorScope();
  VtkErrorScope(const VtkErrorScope&) = delete;
  VtkErrorScope& operator=(const VtkErrorScope&) = delete;

  // OK when VTK raised no error since the scope began; else INTERNAL
  // "<what>: VTK: <first error>" (and how many more).
  Status status(std::string_view what) const;

 private:
  VtkErrorScope* m_outer;  // scopes nest per thread
};

}  // namespace crackvis::render
