// The thin client's core and window against real services: crackvis-data and
// crackvis-render started in this process on loopback ports with generated
// certificates (tests/server/render_fixture.hpp), frames decoded by the
// client's own decoder thread. Widgets run under QT_QPA_PLATFORM=offscreen.
#include <QApplication>
#include <QComboBox>
#include <QSignalSpy>
#include <QSlider>
#include <QTest>
#include <QTreeWidget>
#include <cmath>
#include <filesystem>

#include <catch2/catch.hpp>

#include "dataservice/service_fixture.hpp"
#include "server/render_fixture.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/client/main_window.hpp>
#include <crackvis/client/pipeline_panel.hpp>
#include <crackvis/client/render_client.hpp>

using namespace crackvis;
using namespace crackvis::testing;

namespace {

// One QApplication per process, offscreen.
QApplication& application() {
  static int argc = 1;
  static char name[] = "crackvis_client_tests";
  static char* argv[] = {name, nullptr};
  static QApplication* app = [] {
    qputenv("QT_QPA_PLATFORM", "offscreen");
    return new QApplication(argc, argv);
  }();
  return *app;
}

client::ConnectionSettings settingsFor(const service::RenderServer& server) {
  const auto tls = clientTls("client");
  return {QStringLiteral("localhost:%1").arg(server.port()), QString::fromStdString(tls.ca),
          QString::fromStdString(tls.cert), QString::fromStdString(tls.key), QString()};
}

// Frames received through the signal (the event loop runs while waiting).
struct FrameLog {
  std::vector<QImage> images;
  std::vector<client::FrameInfo> infos;
  explicit FrameLog(client::RenderClient& c) {
    QObject::connect(&c, &client::RenderClient::frameReady,
                     [this](const QImage& image, const client::FrameInfo& info) {
                       images.push_back(image);
                       infos.push_back(info);
                     });
  }
};

bool spinUntil(const std::function<bool()>& done, int milliseconds = 30000) {
  QElapsedTimer timer;
  timer.start();
  while (!done() && timer.elapsed() < milliseconds) {
    QTest::qWait(10);
  }
  return done();
}

double difference(const QImage& a, const QImage& b) {
  if (a.size() != b.size() || a.isNull()) {
    return 255.0;
  }
  const QImage x = a.convertToFormat(QImage::Format_RGB888);
  const QImage y = b.convertToFormat(QImage::Format_RGB888);
  double sum = 0.0;
  for (int row = 0; row < x.height(); ++row) {
    const uchar* p = x.constScanLine(row);
    const uchar* q = y.constScanLine(row);
    for (int k = 0; k < x.width() * 3; ++k) {
      sum += std::abs(p[k] - q[k]);
    }
  }
  return sum / (x.width() * x.height() * 3.0);
}

}  // namespace

TEST_CASE("the client core opens a session, decodes, steers and records", "[client][integration]") {
  application();
  auto services = startServices();
  client::RenderClient client;
  REQUIRE(client.connectTo(settingsFor(*services.render)).isOk());
  auto files = client.listFiles();
  REQUIRE(files.isOk());
  CHECK(std::any_of(files->begin(), files->end(),
                    [](const auto& f) { return f.path == QStringLiteral("cuboidA.h5"); }));
  auto summary = client.describe(QStringLiteral("cuboidA.h5"));
  REQUIRE(summary.isOk());
  CHECK(summary->steps > 10);
  CHECK(summary->particles > 1000);

  FrameLog log(client);
  REQUIRE(client.openSession(QString::fromStdString(pipeline::toXml(crackView()))).isOk());
  REQUIRE(spinUntil([&] { return !log.images.empty(); }));
  const QImage first = log.images.back();
  CHECK(first.size() == QSize(320, 240));

  // 40 rotate events: frames keep coming (the GUI takes the newest), and
  // the picture turns.
  testing::TempDir out;
  const std::string movie = out.file("drag.mp4");
  REQUIRE(client.startRecording(QString::fromStdString(movie)).isOk());
  quint64 last = 0;
  for (int k = 0; k < 40; ++k) {
    last = client.rotate(0.01, 0.0);
    QTest::qWait(15);
  }
  REQUIRE(spinUntil([&] {
    return !log.infos.empty() && log.infos.back().lastEventId >= last &&
           log.infos.back().fullResolution;
  }));
  CHECK(client.statistics().framesDecoded >= 30);
  CHECK(difference(first, log.images.back()) > 2.0);
  CHECK(client.statistics().latencyMs > 0.0);

  // A step change changes the picture.
  const QImage turned = log.images.back();
  const quint64 stepEvent = client.setStep(0);
  REQUIRE(spinUntil([&] {
    return log.infos.back().lastEventId >= stepEvent && log.infos.back().fullResolution;
  }));
  CHECK(log.infos.back().step == 0);
  CHECK(difference(turned, log.images.back()) > 1.0);

  REQUIRE(client.stopRecording().isOk());
  const auto probe = runProcess(
      {"ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
       "stream=codec_name,width,height,nb_read_frames", "-of", "csv=p=0", movie});
  INFO(probe.err);
  REQUIRE(probe.exitCode == 0);
  const QStringList fields = QString::fromStdString(probe.out).trimmed().split(QLatin1Char(','));
  REQUIRE(fields.size() == 4);
  CHECK(fields[0] == QStringLiteral("h264"));
  CHECK(fields[1] == QStringLiteral("320"));
  // Every access unit received from the keyframe on is in the file.
  CHECK(client.recordedFrames() >= 10);
  CHECK(fields[3].toLongLong() == client.recordedFrames());

  // A bad step comes back as a readable event error.
  QSignalSpy failed(&client, &client::RenderClient::eventFailed);
  client.setStep(100000);
  REQUIRE(spinUntil([&] { return failed.count() > 0; }));
  CHECK(failed.takeFirst().at(1).toString().contains(QStringLiteral("out of range")));
  client.closeSession();
  CHECK(spinUntil([&] { return services.render->sessionCount() == 0; }, 5000));
}

TEST_CASE("the client reconnects when the render server restarts", "[client][integration]") {
  application();
  auto services = startServices();
  const int port = services.render->port();
  client::RenderClient client;
  REQUIRE(client.connectTo(settingsFor(*services.render)).isOk());
  FrameLog log(client);
  QSignalSpy lost(&client, &client::RenderClient::connectionLost);
  REQUIRE(client.openSession(QString::fromStdString(pipeline::toXml(crackView()))).isOk());
  REQUIRE(spinUntil([&] { return !log.images.empty(); }));

  services.render->shutdown(0.2);
  services.render.reset();
  REQUIRE(spinUntil([&] { return lost.count() > 0; }, 10000));
  const std::size_t before = log.images.size();
  services.render = startRenderServer(*services.data, fmt::format("127.0.0.1:{}", port));
  // The session was lost with the server: the client opens a new one with
  // the same pipeline and step, and frames come again.
  REQUIRE(spinUntil([&] { return log.images.size() > before; }, 30000));
  CHECK(services.render->sessionCount() == 1);
  CHECK(log.images.back().size() == QSize(320, 240));
  client.rotate(0.05, 0.0);
  CHECK(spinUntil([&] { return log.images.size() > before + 1; }, 10000));
}

TEST_CASE("the window connects, opens a file, switches the method and steps",
          "[client][ui][integration]") {
  application();
  auto services = startServices();
  client::MainWindow window;
  window.resize(900, 600);
  window.show();
  REQUIRE(window.connectTo(settingsFor(*services.render)));
  QTreeWidget& tree = window.fileTree();
  QTreeWidgetItem* item = nullptr;
  for (int k = 0; k < tree.topLevelItemCount(); ++k) {
    if (tree.topLevelItem(k)->text(0) == QStringLiteral("cuboidA.h5")) {
      item = tree.topLevelItem(k);
    }
  }
  REQUIRE(item != nullptr);
  tree.setCurrentItem(item);
  emit tree.itemActivated(item, 0);
  REQUIRE(spinUntil([&] { return window.viewport().framesShown() > 0; }));

  int shown = window.viewport().framesShown();
  QComboBox* method = window.pipelinePanel().methodBox();
  method->setCurrentIndex(method->findText(QStringLiteral("cell cut")));
  REQUIRE(spinUntil([&] { return window.viewport().framesShown() > shown; }));
  CHECK(spinUntil(
      [&] { return window.client().pipelineXml().contains(QStringLiteral("cell-cut")); }, 5000));

  shown = window.viewport().framesShown();
  window.stepSlider().setValue(3);
  REQUIRE(spinUntil([&] { return window.viewport().framesShown() > shown; }));
  CHECK(spinUntil([&] { return window.client().step() == 3; }, 10000));
  CHECK(window.messages().contains(QStringLiteral("opened cuboidA.h5")));
  // Cell cut draws cuboid A's scattered breaks as lines, not faces: the
  // server's warning reaches the status bar and the messages pane, once.
  CHECK(spinUntil([&] { return window.lastMessage().startsWith(QStringLiteral("warning: only ")); },
                  5000));
  CHECK(window.messages().count(QStringLiteral("isolated breaks")) == 1);
}

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
