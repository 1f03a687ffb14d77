#include <cstdlib>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include <crackvis/common/huge_pages.hpp>

namespace crackvis {
namespace {

constexpr std::string_view kHugetlbTunable = "glibc.malloc.hugetlb";

std::string readThpMode() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

std::optional<std::string> hugePageTunables(std::string_view thpMode, const char* tunables,
                                            const char* setting) {
  if (setting != nullptr && std::string_view(setting) == "0") {
    return std::nullopt;
  }
  if (thpMode.find("[madvise]") == std::string_view::npos) {
    return std::nullopt;
  }
  const std::string_view present = tunables != nullptr ? tunables : "";
  if (present.find(kHugetlbTunable) != std::string_view::npos) {
    return std::nullopt;  // set by the user, or by this process's first start
  }
  std::string wanted = std::string(kHugetlbTunable) + "=1";
  return present.empty() ? wanted : std::string(present) + ":" + wanted;
}

void reexecWithHugePages(char** argv) {
  const auto tunables = hugePageTunables(readThpMode(), std::getenv("GLIBC_TUNABLES"),
                                         std::getenv(kHugePagesVariable));
  if (!tunables || argv == nullptr || argv[0] == nullptr) {
    return;
  }
  if (setenv("GLIBC_TUNABLES", tunables->c_str(), 1) != 0) {
    return;
  }
  execv("/proc/self/exe", argv);
  // Only a failed exec returns: run on, on small pages. The variable stays
  // set, so that a child this process starts does not try again.
}

}  // namespace crackvis
