#include "reduction_policy.hpp"

#include <algorithm>

namespace crackvis::service {

namespace {
// Coarse from this share of recent frames crowded, full again below the
// second: apart, so that the faster coarse frames, which meet others less
// often, do not switch the detail back and forth.
constexpr double kCoarseFrom = 0.5;
constexpr double kFullBelow = 0.2;
constexpr double kRecent = 0.3;  // weight of the latest frame in the averages
}  // namespace

ReductionPolicy::ReductionPolicy(const SessionLimits& limits)
    : m_mostReduction(std::min(limits.maxReduction, kMaxReduction)),
      m_budgetMs(limits.interactiveFrameMs) {
  // The start value may exceed a low limit. The limits are fixed and
  // adaptFactor never goes above mostReduction(), so clamping once here
  // equals clamping before every frame.
  m_reduction = std::min(m_reduction, mostReduction());
}

void ReductionPolicy::adapt(double renderMs, double turnWaitMs, bool coarse,
                            std::optional<bool> crowded) {
  adaptFactor(renderMs + turnWaitMs, coarse);
  if (crowded) {
    adaptDetail(*crowded);
  }
}

void ReductionPolicy::newDrag() {
  m_crowdedShare = 0.0;
  m_coarse = false;
}

void ReductionPolicy::adaptDetail(bool crowded) {
  m_crowdedShare = (1.0 - kRecent) * m_crowdedShare + kRecent * (crowded ? 1.0 : 0.0);
  m_coarse = m_coarse ? m_crowdedShare >= kFullBelow : m_crowdedShare >= kCoarseFrom;
}

// The times known at the frame's own detail choose the next factor.
void ReductionPolicy::adaptFactor(double frameMs, bool coarse) {
  auto& timeAt = m_timeAt[coarse ? 1 : 0];
  auto& known = timeAt[static_cast<std::size_t>(m_reduction)];
  known = known > 0.0 ? (1.0 - kRecent) * known + kRecent * frameMs : frameMs;
  const double budget = m_budgetMs;
  const int most = mostReduction();
  const double larger =
      m_reduction < most ? timeAt[static_cast<std::size_t>(m_reduction + 1)] : 0.0;
  const double smaller = m_reduction > 1 ? timeAt[static_cast<std::size_t>(m_reduction - 1)] : 0.0;
  if (known > budget && m_reduction < most && (larger == 0.0 || larger < 0.95 * known)) {
    ++m_reduction;
  } else if (m_reduction > 1 && ((smaller > 0.0 && (smaller <= budget || smaller < 1.15 * known)) ||
                                 (smaller == 0.0 && known < 0.5 * budget))) {
    --m_reduction;
  }
}

}  // namespace crackvis::service
