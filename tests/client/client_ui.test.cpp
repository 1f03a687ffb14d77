// The thin client without services: its widgets under
// QT_QPA_PLATFORM=offscreen, and crackvis-client's answers to a missing
// display and a misspelt option. Builds in the client's own tree
// (CRACKVIS_CLIENT_ONLY); the tests against real services are
// render_client.test.cpp and client_app.test.cpp.
#include <QApplication>
#include <QCheckBox>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QLineEdit>
#include <QSignalSpy>
#include <QTest>
#include <chrono>
#include <cmath>
#include <thread>

#include <catch2/catch.hpp>

#include "client/client_process.hpp"
#include <crackvis/client_ui/pipeline_panel.hpp>
#include <crackvis/client_ui/step_plot.hpp>
#include <crackvis/client_ui/viewport.hpp>

using namespace crackvis;
using namespace crackvis::testing;

namespace {

// One QApplication per process, offscreen.
QApplication& application() {
  static int argc = 1;
  static char name[] = "crackvis_client_ui_tests";
  static char* argv[] = {name, nullptr};
  static QApplication* app = [] {
    qputenv("QT_QPA_PLATFORM", "offscreen");
    return new QApplication(argc, argv);
  }();
  return *app;
}

}  // namespace

TEST_CASE("the pipeline panel offers a file's extra arrays under colour by", "[client]") {
  application();
  client::PipelinePanel panel;
  pipeline::PipelineDescription changed;
  QObject::connect(&panel, &client::PipelinePanel::changed,
                   [&](const pipeline::PipelineDescription& d) { changed = d; });
  panel.setExtras({"damage", "nbCracks"}, {"forceN"});
  QComboBox* box = panel.particleColourBox();
  REQUIRE(box->findText("extra: damage") >= 0);
  box->setCurrentIndex(box->findText("extra: nbCracks"));
  CHECK(changed.particles.colourBy == pipeline::ParticleColourBy::kExtra);
  CHECK(changed.particles.colourByExtra == "nbCracks");
  CHECK_THAT(pipeline::toXml(changed), Catch::Contains("colour-by=\"extra:nbCracks\""));
  QComboBox* bonds = panel.bondColourBox();
  bonds->setCurrentIndex(bonds->findText("extra: forceN"));
  CHECK(changed.bonds.colourBy == pipeline::BondColourBy::kExtra);
  CHECK(changed.bonds.colourByExtra == "forceN");
  CHECK_THAT(pipeline::toXml(changed), Catch::Contains("colour-by=\"extra:forceN\""));
  // Another file's arrays replace these ones.
  panel.setExtras({"force"}, {});
  CHECK(box->findText("extra: damage") < 0);
  CHECK(box->findText("extra: force") >= 0);
  CHECK(bonds->findText("extra: forceN") < 0);
}

TEST_CASE("the panel's clip, threshold and colour range reach every layer", "[client][ui]") {
  application();
  client::PipelinePanel panel;
  QSignalSpy changed(&panel, &client::PipelinePanel::changed);
  const auto& cracks = panel.crackControls();
  const auto& bonds = panel.bondControls();
  panel.clipNormal(0)->setValue(0.0);
  panel.clipNormal(2)->setValue(1.0);
  panel.clipOrigin(2)->setValue(0.05);
  cracks.clip->setChecked(true);
  bonds.clip->setChecked(true);
  const auto& d1 = panel.description();
  REQUIRE(d1.cracks.clip.has_value());
  CHECK(d1.cracks.clip->normal == dem::Vec3{0, 0, 1});
  CHECK(d1.cracks.clip->origin.z == Approx(0.05));
  REQUIRE(d1.bonds.clip.has_value());
  CHECK_FALSE(d1.particles.clip.has_value());

  cracks.thresholdBy->setCurrentIndex(cracks.thresholdBy->findText(QStringLiteral("break step")));
  cracks.thresholdMin->setText(QStringLiteral("100"));
  cracks.threshold->setChecked(true);
  const auto& d2 = panel.description();
  REQUIRE(d2.cracks.threshold.has_value());
  CHECK(d2.cracks.threshold->by == pipeline::CrackColourBy::kBreakStep);
  CHECK(d2.cracks.threshold->min == 100.0);
  CHECK(std::isinf(d2.cracks.threshold->max));

  const auto& particles = panel.particleControls();
  particles.rangeMin->setText(QStringLiteral("-0.5"));
  particles.rangeMax->setText(QStringLiteral("2e-3"));
  particles.rangeMode->setCurrentIndex(particles.rangeMode->findText(QStringLiteral("set")));
  const auto& d3 = panel.description();
  CHECK(d3.particles.range.mode == pipeline::RangeMode::kUser);
  CHECK(d3.particles.range.min == -0.5);
  CHECK(d3.particles.range.max == 0.002);
  CHECK(changed.count() >= 4);
  // What the panel makes is a valid document that says the same.
  pipeline::PipelineDescription made = panel.description();
  made.file = "cuboidA.h5";  // the window adds the file it opened
  auto parsed = pipeline::parsePipeline(pipeline::toXml(made));
  INFO(parsed.status().message());
  REQUIRE(parsed.isOk());
  CHECK(*parsed == made);
  // And a description shown comes back unchanged.
  client::PipelinePanel other;
  other.setDescription(*parsed);
  CHECK(other.crackControls().threshold->isChecked());
  CHECK(other.crackControls().thresholdMin->text() == QStringLiteral("100"));
  CHECK(other.particleControls().rangeMax->text() == QStringLiteral("0.002"));
}

TEST_CASE("the panel colours cracks by opening or slip and particles by fragment",
          "[client][ui][analysis]") {
  application();
  client::PipelinePanel panel;
  const auto& cracks = panel.crackControls();
  cracks.thresholdBy->setCurrentIndex(cracks.thresholdBy->findText(QStringLiteral("opening")));
  cracks.thresholdMin->setText(QStringLiteral("1e-4"));
  cracks.threshold->setChecked(true);
  const auto& particles = panel.particleControls();
  particles.thresholdBy->setCurrentIndex(
      particles.thresholdBy->findText(QStringLiteral("fragment")));
  particles.thresholdMax->setText(QStringLiteral("3"));
  particles.threshold->setChecked(true);
  pipeline::PipelineDescription made = panel.description();
  REQUIRE(made.cracks.threshold.has_value());
  CHECK(made.cracks.threshold->by == pipeline::CrackColourBy::kOpening);
  REQUIRE(made.particles.threshold.has_value());
  CHECK(made.particles.threshold->by == pipeline::ParticleColourBy::kFragment);
  made.file = "run.h5";
  const std::string xml = pipeline::toXml(made);
  CHECK_THAT(xml, Catch::Contains("by=\"opening\"") && Catch::Contains("by=\"fragment\""));
  auto parsed = pipeline::parsePipeline(xml);
  INFO(parsed.status().message());
  REQUIRE(parsed.isOk());
  CHECK(*parsed == made);
  made.cracks.colourBy = pipeline::CrackColourBy::kSlip;
  CHECK(pipeline::parsePipeline(pipeline::toXml(made)).isOk());
}

TEST_CASE("the step plot draws a chosen step scalar beside the broken bonds", "[client][ui]") {
  application();
  client::StepPlot plot;
  plot.resize(400, 200);
  client::StepHistory history;
  history.time = {0.0, 1.0, 2.0, 3.0};
  history.brokenBonds = {0, 1, 3, 6};
  history.bondCount = 10;
  history.scalarNames = {QStringLiteral("load")};
  history.scalars = {{0.0, 5.0, std::nan(""), 2.0}};
  plot.setHistory(history);
  auto pixelsOf = [&](QColor colour) {
    const QImage image = plot.grab().toImage().convertToFormat(QImage::Format_RGB888);
    int n = 0;
    for (int y = 0; y < image.height(); ++y) {
      for (int x = 0; x < image.width(); ++x) {
        const QColor c = image.pixelColor(x, y);
        n += std::abs(c.red() - colour.red()) + std::abs(c.green() - colour.green()) +
                         std::abs(c.blue() - colour.blue()) <
                     30
                 ? 1
                 : 0;
      }
    }
    return n;
  };
  const QColor scalarColour(0x4c, 0xc9, 0xf0);
  const QColor brokenColour(0xff, 0x9f, 0x1c);
  CHECK(pixelsOf(brokenColour) > 50);
  CHECK(pixelsOf(scalarColour) == 0);
  REQUIRE(plot.setScalar(QStringLiteral("load")));
  CHECK(plot.scalar() == QStringLiteral("load"));
  CHECK(pixelsOf(scalarColour) > 50);
  CHECK_FALSE(plot.setScalar(QStringLiteral("energy")));
  CHECK(pixelsOf(scalarColour) == 0);
  CHECK(plot.stepAt(plot.plotArea().right()) == 3);
  CHECK(plot.stepAt(-100) == 0);

  // Against the load (5 at step 1, highest): its right end is step 1, its
  // left end step 0 (load 0); step 2 has no load and is left out.
  CHECK(plot.axisNames() == QStringList({QStringLiteral("step"), QStringLiteral("time"),
                                         QStringLiteral("broken bonds"), QStringLiteral("load")}));
  REQUIRE(plot.setAxis(QStringLiteral("load")));
  CHECK(plot.axis() == QStringLiteral("load"));
  CHECK(plot.stepAt(plot.plotArea().right()) == 1);
  CHECK(plot.stepAt(plot.plotArea().left()) == 0);
  const QRect area = plot.plotArea();
  CHECK(plot.stepAt(area.left() + area.width() * 2 / 5) == 3);  // load 2
  REQUIRE(plot.setScalar(QStringLiteral("load")));
  CHECK(pixelsOf(scalarColour) > 50);
  CHECK_FALSE(plot.setAxis(QStringLiteral("energy")));
  CHECK(plot.axis() == QStringLiteral("step"));
  // Against the broken bonds (0, 1, 3, 6): their range maps to the width.
  REQUIRE(plot.setAxis(QStringLiteral("broken bonds")));
  CHECK(plot.stepAt(area.left() + area.width() / 2) == 2);  // 3 of 6
}

TEST_CASE("crackvis-client without a display says what to run instead", "[client]") {
  const std::string expected =
      "crackvis-client: no display (DISPLAY and WAYLAND_DISPLAY are not set): run the scripted "
      "session without a window with --demo FOLDER, or the window off screen with "
      "QT_QPA_PLATFORM=offscreen\n";
  for (const auto& platform :
       {std::vector<std::string>{}, std::vector<std::string>{"QT_QPA_PLATFORM=xcb"},
        std::vector<std::string>{"QT_QPA_PLATFORM=wayland"}}) {
    auto environment = kNoDisplay;
    environment.insert(environment.end(), platform.begin(), platform.end());
    const auto result = runClient(environment, {"--connect", "localhost:50052"});
    CHECK(result.exitCode == 2);  // not Qt's abort (134)
    CHECK(result.err == expected);
  }
  // --help needs no display.
  const auto help = runClient(kNoDisplay, {"--help"});
  CHECK(help.exitCode == 0);
  CHECK_THAT(help.out, Catch::Contains("--window-screenshot"));
}

TEST_CASE("the viewport times each event from its send to the first painted frame reflecting it",
          "[client][ui]") {
  application();
  client::RenderClient connection;
  client::Viewport view(connection);
  view.resize(320, 240);
  view.show();
  std::vector<std::vector<double>> paints;
  QObject::connect(&view, &client::Viewport::painted,
                   [&](const std::vector<double>& latencies, const client::FrameInfo&) {
                     paints.push_back(latencies);
                   });
  QImage picture(320, 240, QImage::Format_RGB888);
  picture.fill(Qt::darkGray);
  const auto sent = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  // Two frames shown before one paint: the events of the first are
  // reflected first by the frame painted, so they are timed with it.
  client::FrameInfo first;
  first.eventsSentAt = {sent, sent + std::chrono::milliseconds(10)};
  client::FrameInfo second;
  second.eventsSentAt = {sent + std::chrono::milliseconds(20)};
  view.showFrame(picture, first);
  view.showFrame(picture, second);
  REQUIRE(QTest::qWaitFor([&] { return !paints.empty(); }, 5000));
  const auto elapsed =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - sent).count();
  REQUIRE(paints.back().size() == 3);
  CHECK(paints.back()[0] >= 30.0);
  CHECK(paints.back()[0] <= elapsed);
  CHECK(paints.back()[0] - paints.back()[1] == Approx(10.0).margin(0.01));
  CHECK(paints.back()[0] - paints.back()[2] == Approx(20.0).margin(0.01));
  CHECK(view.paintLatencyMs() == Approx(paints.back()[1]));
  // A frame reflecting no new event is painted with none, and a repaint of
  // it is no new frame.
  const std::size_t before = paints.size();
  view.showFrame(picture, client::FrameInfo{});
  REQUIRE(QTest::qWaitFor([&] { return paints.size() > before; }, 5000));
  CHECK(paints.back().empty());
  view.repaint();
  CHECK(paints.size() == before + 1);
}

TEST_CASE("crackvis-client --measure-latency says what it needs", "[client]") {
  const auto noFile =
      runClient(kOffscreen, {"--connect", "localhost:50052", "--measure-latency", "-"});
  CHECK(noFile.exitCode == 2);
  CHECK(
      clientLines(noFile.err) ==
      std::vector<std::string>{"crackvis-client: --measure-latency needs --connect and --file (or "
                               "a --pipeline view that names a file)"});
  const auto badSize = runClient(kOffscreen, {"--connect", "localhost:50052", "--file", "a.h5",
                                              "--measure-latency", "-", "--view-size", "641x480"});
  CHECK(badSize.exitCode == 2);
  CHECK(clientLines(badSize.err) ==
        std::vector<std::string>{
            "crackvis-client: --view-size 641x480: expected WxH, even, at least 320x240"});
  const auto badSeconds = runClient(kOffscreen, {"--connect", "localhost:50052", "--file", "a.h5",
                                                 "--measure-latency", "-", "--drag-seconds", "x"});
  CHECK(badSeconds.exitCode == 2);
  CHECK(clientLines(badSeconds.err) ==
        std::vector<std::string>{"crackvis-client: --drag-seconds x: expected 0.5 to 600 seconds"});
  const auto both =
      runClient(kOffscreen, {"--connect", "localhost:50052", "--file", "a.h5", "--measure-latency",
                             "-", "--window-screenshot", "a.png"});
  CHECK(both.exitCode == 2);
  CHECK(clientLines(both.err) ==
        std::vector<std::string>{"crackvis-client: --measure-latency runs the window alone: "
                                 "leave out --window-screenshot"});
}

TEST_CASE("crackvis-client names a misspelt option and the nearest one", "[client]") {
  const auto typo = runClient(kOffscreen, {"--conect", "localhost:50052"});
  CHECK(typo.exitCode == 2);
  CHECK(clientLines(typo.err) ==
        std::vector<std::string>{
            "crackvis-client: unknown option '--conect' (did you mean --connect?)"});
  const auto unknown = runClient(kOffscreen, {"--frobnicate"});
  CHECK(unknown.exitCode == 2);
  CHECK(clientLines(unknown.err) ==
        std::vector<std::string>{"crackvis-client: unknown option '--frobnicate'"});
}
