// A step source that forwards every call to another one: tests derive from
// it to change one answer (a read that throws, a Describe time) and keep a
// real file's source underneath.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <crackvis/source/step_source.hpp>

namespace crackvis::testing {

class ForwardingSource : public source::StepSource {
 public:
  explicit ForwardingSource(std::unique_ptr<source::StepSource> inner)
      : m_inner(std::move(inner)) {}
  const std::string& file() const override { return m_inner->file(); }
  const dem::Lattice& lattice() const override { return m_inner->lattice(); }
  int stepCount() const override { return m_inner->stepCount(); }
  Status setExtraArrays(const source::ExtraArrays& extras) override {
    return m_inner->setExtraArrays(extras);
  }
  const std::vector<std::int32_t>& breakSteps() const override { return m_inner->breakSteps(); }
  Result<source::SourceStep> read(int step) override { return m_inner->read(step); }
  bool timeInIterations() const override { return m_inner->timeInIterations(); }
  bool appendable() const override { return m_inner->appendable(); }
  bool beingWritten() const override { return m_inner->beingWritten(); }
  Result<bool> refresh() override { return m_inner->refresh(); }
  double describeMs() const override { return m_inner->describeMs(); }
  dem::CellDecomposition recordedDecomposition() const override {
    return m_inner->recordedDecomposition();
  }

 private:
  std::unique_ptr<source::StepSource> m_inner;
};

}  // namespace crackvis::testing
