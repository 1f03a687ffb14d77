#include "reduction_policy.hpp"

#include <algorithm>

namespace crackvis::service {

ReductionPolicy::ReductionPolicy(const SessionLimits& limits)
    : m_mostReduction(std::min(limits.maxReduction, kMaxReduction)),
      m_budgetMs(limits.interactiveFrameMs) {
  // The start value may exceed a low limit. The limits are fixed and
  // adaptReduction never goes above mostReduction(), so clamping once here
  // equals clamping before every frame.
  m_reduction = std::min(m_reduction, mostReduction());
}

void ReductionPolicy::adaptReduction(double renderMs) {
  auto& known = m_timeAt[static_cast<std::size_t>(m_reduction)];
  known = known > 0.0 ? 0.7 * known + 0.3 * renderMs : renderMs;
  const double budget = m_budgetMs;
  const int most = mostReduction();
  const double larger =
      m_reduction < most ? m_timeAt[static_cast<std::size_t>(m_reduction + 1)] : 0.0;
  const double smaller =
      m_reduction > 1 ? m_timeAt[static_cast<std::size_t>(m_reduction - 1)] : 0.0;
  if (known > budget && m_reduction < most && (larger == 0.0 || larger < 0.95 * known)) {
    ++m_reduction;
  } else if (m_reduction > 1 && ((smaller > 0.0 && (smaller <= budget || smaller < 1.15 * known)) ||
                                 (smaller == 0.0 && known < 0.5 * budget))) {
    --m_reduction;
  }
}

}  // namespace crackvis::service
