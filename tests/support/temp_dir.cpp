#include "support/temp_dir.hpp"

#include <cstdlib>
#include <stdexcept>

namespace crackvis::testing {

TempDir::TempDir() {
  std::string pattern = (std::filesystem::temp_directory_path() / "crackvis-test-XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) {
    throw std::runtime_error("mkdtemp failed for " + pattern);
  }
  m_path = pattern;
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(m_path, ignored);
}

}  // namespace crackvis::testing
