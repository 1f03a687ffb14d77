// The thin client's core and window against real services: crackvis-data and
// crackvis-render started in this process on loopback ports with generated
// certificates (tests/service/render_fixture.hpp), frames decoded by the
// client's own decoder thread. Widgets run under QT_QPA_PLATFORM=offscreen.
#include <QAction>
#include <QApplication>
#include <QCheckBox>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QFile>
#include <QLabel>
#include <QLineEdit>
#include <QPushButton>
#include <QSignalSpy>
#include <QSlider>
#include <QTest>
#include <QTreeWidget>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "dataservice/service_fixture.hpp"
#include "service/render_fixture.hpp"
#include "support/full_disk.hpp"
#include "support/network.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/client_core/render_client.hpp>
#include <crackvis/client_ui/main_window.hpp>
#include <crackvis/client_ui/pipeline_panel.hpp>
#include <crackvis/client_ui/step_plot.hpp>
#include <crackvis/dem/dem_file.hpp>

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

TEST_CASE("the client says what is wrong with the server it was pointed at",
          "[client][integration]") {
  application();
  auto services = startServices();
  client::RenderClient client;
  auto settings = settingsFor(*services.render);
  SECTION("nothing listens there") {
    const int port = closedPort();
    settings.address = QStringLiteral("localhost:%1").arg(port);
    const Status status = client.connectTo(settings);
    CHECK(status.code() == StatusCode::kUnavailable);
    CHECK(status.message() == fmt::format("no crackvis-render at localhost:{} (connection "
                                          "refused): is it running? see docs/deploy.md",
                                          port));
  }
  SECTION("the data service's port") {
    settings.address = QStringLiteral("localhost:%1").arg(services.data->port());
    const Status status = client.connectTo(settings);
    CHECK(status.code() == StatusCode::kFailedPrecondition);
    CHECK(status.message() == fmt::format("localhost:{} is a crackvis-data, not a crackvis-render",
                                          services.data->port()));
  }
  SECTION("a render server on --insecure") {
    auto config = renderConfig(*services.data);
    config.insecure = true;
    auto plain = startRenderServer(config);
    settings.address = QString::fromStdString(plain->address());
    const Status status = client.connectTo(settings);
    CHECK(status.message() ==
          fmt::format("{} speaks plaintext (a crackvis-render started with --insecure), not TLS, "
                      "and this client connects only with TLS: start the server with its "
                      "certificates (docs/security.md)",
                      plain->address()));
  }
  SECTION("an address without a port") {
    settings.address = QStringLiteral("localhost");
    const Status status = client.connectTo(settings);
    CHECK(status.code() == StatusCode::kInvalidArgument);
    CHECK_THAT(status.message(),
               Catch::StartsWith("address 'localhost': expected HOST:PORT with the port"));
  }
  SECTION("a certificate that is not there") {
    settings.caPath = QStringLiteral("/nonexistent/ca.pem");
    const Status status = client.connectTo(settings);
    CHECK(status.message() ==
          "cannot read CA certificate '/nonexistent/ca.pem': No such file or "
          "directory (set by --ca or in File > Connect)");
  }
  CHECK_FALSE(client.connected());
  // The right address, for contrast.
  CHECK(client.connectTo(settingsFor(*services.render)).isOk());
}

TEST_CASE("the window shows a step the file lacks as the server's error, not another step",
          "[client][ui][integration]") {
  application();
  auto services = startServices();
  client::MainWindow window;
  window.resize(900, 600);
  window.show();
  REQUIRE(window.connectTo(settingsFor(*services.render)));
  auto summary = window.client().describe(QStringLiteral("cuboidA.h5"));
  REQUIRE(summary.isOk());
  const int steps = summary->steps;
  REQUIRE(steps > 3);

  CHECK_FALSE(window.openFile(QStringLiteral("cuboidA.h5"), steps + 100));
  const QString expected =
      QStringLiteral("cuboidA.h5: step %1 out of range (the file has steps 0..%2)")
          .arg(steps + 100)
          .arg(steps - 1);
  CHECK(window.lastMessage().contains(expected));
  CHECK(window.messages().contains(expected));
  CHECK_FALSE(window.client().hasSession());

  // A step the file has is the one shown.
  REQUIRE(window.openFile(QStringLiteral("cuboidA.h5"), 2));
  REQUIRE(spinUntil([&] { return window.viewport().framesShown() > 0; }));
  CHECK(window.client().step() == 2);
  CHECK(window.stepSlider().value() == 2);
}

namespace {

// The window with cuboidA.h5 open and a frame shown.
void openCuboid(client::MainWindow& window, const service::RenderServer& server) {
  window.resize(900, 600);
  window.show();
  REQUIRE(window.connectTo(settingsFor(server)));
  REQUIRE(window.openFile(QStringLiteral("cuboidA.h5")));
  REQUIRE(spinUntil([&] { return window.viewport().framesShown() > 0; }));
}

std::optional<pipeline::CameraDescription> cameraOf(const QString& xml) {
  auto d = pipeline::parsePipeline(xml.toStdString());
  REQUIRE(d.isOk());
  return d->view.camera;
}

// The full-resolution frame that follows the last event sent.
QImage settledFrame(FrameLog& log, quint64 event) {
  REQUIRE(spinUntil([&] {
    return !log.infos.empty() && log.infos.back().lastEventId >= event &&
           log.infos.back().fullResolution;
  }));
  return log.images.back();
}

}  // namespace

TEST_CASE("a saved view opens again as it was: file, step, camera, another file is fitted",
          "[client][ui][integration]") {
  application();
  auto services = startServices();
  testing::TempDir out;
  const QString viewPath = QString::fromStdString(out.file("view.xml"));
  QImage saved;  // rendered by the server (PNG): the picture itself, no codec between
  pipeline::CameraDescription savedCamera;
  {
    client::MainWindow window;
    openCuboid(window, *services.render);
    FrameLog log(window.client());
    window.stepSlider().setValue(3);
    REQUIRE(spinUntil([&] { return window.client().step() == 3; }, 10000));
    const auto opened = cameraOf(window.client().pipelineXml());
    REQUIRE(opened.has_value());
    window.client().rotate(0.15, 0.05);
    window.client().zoom(0.4);
    const quint64 still = window.client().requestStill();
    (void)settledFrame(log, still);
    // The server's state carries the camera once it has come to rest.
    REQUIRE(spinUntil([&] {
      auto camera = cameraOf(window.client().pipelineXml());
      return camera && dem::norm(camera->position - opened->position) > 1e-3;
    }));
    auto png = window.client().snapshotPng();
    REQUIRE(png.isOk());
    saved = QImage::fromData(*png, "PNG");
    // On a full disk the save fails with a message and an earlier view of
    // that name is kept as it was (the client writes through QSaveFile).
    {
      testing::FullDisk disk(64 * 1024, 0);
      const std::string earlier = disk.file("view.xml");
      std::ofstream(earlier) << "an earlier view";
      disk.fill();
      const auto failed = [&] {
        std::optional<testing::FileSizeLimit> limit;  // without a mount: no write may grow a file
        if (!disk.mounted()) {
          limit.emplace(0);
        }
        return !window.saveView(QString::fromStdString(earlier));
      }();
      CHECK(failed);
      CHECK(window.lastMessage().contains(QStringLiteral("cannot write")));
      CHECK(testing::fileText(earlier) == "an earlier view");
    }
    REQUIRE(window.saveView(viewPath));
    CHECK(window.messages().contains(QStringLiteral("saved the view to")));
    QFile file(viewPath);
    REQUIRE(file.open(QIODevice::ReadOnly));
    auto view = pipeline::parsePipeline(file.readAll().toStdString());
    REQUIRE(view.isOk());
    CHECK(view->file == "cuboidA.h5");
    CHECK(view->step == 3);
    CHECK_FALSE(view->clientLayout.empty());  // the window's docks and size
    REQUIRE(view->view.camera.has_value());
    savedCamera = *view->view.camera;
  }
  // A new window (a colleague's) shows the same picture from the file.
  client::MainWindow again;
  again.resize(900, 600);
  again.show();
  REQUIRE(again.connectTo(settingsFor(*services.render)));
  FrameLog log(again.client());
  REQUIRE(again.loadView(viewPath));
  REQUIRE(spinUntil([&] { return !log.infos.empty() && log.infos.back().fullResolution; }));
  CHECK(again.client().step() == 3);
  CHECK(again.stepSlider().value() == 3);
  auto png = again.client().snapshotPng(saved.width(), saved.height());
  REQUIRE(png.isOk());
  const QImage reopened = QImage::fromData(*png, "PNG");
  REQUIRE(reopened.size() == saved.size());
  CHECK(difference(saved, reopened) < 0.5);
  auto shownCamera = cameraOf(again.client().pipelineXml());
  REQUIRE(shownCamera.has_value());
  CHECK(dem::norm(shownCamera->position - savedCamera.position) < 1e-6);

  // Opening a file (this one again, as a user picks it in the browser)
  // fits the camera to it instead of keeping the saved one.
  REQUIRE(again.openFile(QStringLiteral("cuboidA.h5")));
  REQUIRE(spinUntil([&] {
    auto camera = cameraOf(again.client().pipelineXml());
    return camera && dem::norm(camera->position - savedCamera.position) > 1e-3;
  }));

  // Before a file is open there is no view to save.
  client::MainWindow empty;
  CHECK_FALSE(empty.saveView(QString::fromStdString(out.file("empty.xml"))));
  CHECK(empty.lastMessage().contains(QStringLiteral("open a file first")));
  CHECK_FALSE(std::filesystem::exists(out.file("empty.xml")));

  // A file that is no view: one message, nothing changes.
  const std::string bad = out.file("bad.xml");
  std::ofstream(bad) << "<pipeline><particles opacity='2'/></pipeline>";
  CHECK_FALSE(again.loadView(QString::fromStdString(bad)));
  CHECK(again.lastMessage().contains(QStringLiteral("is no view")));
  CHECK(again.client().hasSession());
}

TEST_CASE("screenshots of any size, full-resolution movies, and a recording's menu item",
          "[client][ui][integration]") {
  application();
  auto services = startServices();
  client::MainWindow window;
  openCuboid(window, *services.render);
  testing::TempDir out;

  const QString shot = QString::fromStdString(out.file("shot.png"));
  window.saveScreenshot(shot, QSize(640, 360));
  const QImage picture(shot);
  CHECK(picture.size() == QSize(640, 360));
  // Beyond the server's largest view: its refusal, in the messages pane.
  window.saveScreenshot(QString::fromStdString(out.file("huge.png")), QSize(9000, 9000));
  CHECK(window.lastMessage().contains(QStringLiteral("9000")));
  CHECK_FALSE(std::filesystem::exists(out.file("huge.png")));

  // Steps 0, 2, 4, 6 rendered again on the server at 320x240.
  const int steps = window.client().stepCount();
  REQUIRE(steps > 6);
  const std::string movie = out.file("movie.mp4");
  REQUIRE(window.recordMovie(QString::fromStdString(movie), 0, 6, 2, QSize(320, 240), 10));
  const auto probe =
      runProcess({"ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0",
                  "-show_entries", "stream=width,height,nb_read_frames", "-of", "csv=p=0", movie});
  INFO(probe.err);
  REQUIRE(probe.exitCode == 0);
  CHECK(QString::fromStdString(probe.out).trimmed() == QStringLiteral("320,240,4"));
  CHECK(spinUntil([&] { return window.client().step() == 6; }, 10000));
  // A step the file lacks: the server's refusal, no file left behind.
  const std::string badMovie = out.file("bad.mp4");
  CHECK_FALSE(window.recordMovie(QString::fromStdString(badMovie), steps, steps + 2, 1,
                                 QSize(320, 240), 10));
  INFO(window.messages().toStdString());
  CHECK(window.lastMessage().contains(QStringLiteral("out of range")));
  CHECK_FALSE(std::filesystem::exists(badMovie));

  // The menu says what the item will do.
  auto actionNamed = [&](const QString& prefix) -> QAction* {
    for (QAction* action : window.findChildren<QAction*>()) {
      if (action->text().remove(QLatin1Char('&')).startsWith(prefix)) {
        return action;
      }
    }
    return nullptr;
  };
  REQUIRE(actionNamed(QStringLiteral("Record the stream")) != nullptr);
  window.toggleRecording(QString::fromStdString(out.file("stream.mp4")));
  CHECK(actionNamed(QStringLiteral("Stop recording")) != nullptr);
  CHECK(actionNamed(QStringLiteral("Record the stream")) == nullptr);
  window.toggleRecording();
  CHECK(actionNamed(QStringLiteral("Record the stream")) != nullptr);
}

TEST_CASE("the messages pane folds a repeated error into a count", "[client][ui][integration]") {
  application();
  auto services = startServices();
  client::MainWindow window;
  openCuboid(window, *services.render);
  QSignalSpy failed(&window.client(), &client::RenderClient::eventFailed);
  for (int k = 0; k < 3; ++k) {
    window.client().setStep(100000);
  }
  REQUIRE(spinUntil([&] { return failed.count() >= 3; }));
  QTest::qWait(50);  // the window's own slot runs after the spy's
  const QString log = window.messages();
  CHECK(log.count(QStringLiteral("out of range")) == 1);
  CHECK(log.contains(QStringLiteral("(3 times)")));
  // A different message starts a line of its own.
  window.client().setStep(100001);
  REQUIRE(spinUntil([&] { return failed.count() >= 4; }));
  QTest::qWait(50);
  CHECK(window.messages().count(QStringLiteral("out of range")) == 2);
}

TEST_CASE("a double click shows the values of the particle under it", "[client][ui][integration]") {
  application();
  auto services = startServices();
  client::MainWindow window;
  openCuboid(window, *services.render);
  QSignalSpy picked(&window.client(), &client::RenderClient::picked);
  const QRect picture = window.viewport().pictureRect();
  QTest::mouseDClick(&window.viewport(), Qt::LeftButton, Qt::NoModifier, picture.center());
  REQUIRE(spinUntil([&] { return picked.count() > 0; }, 10000));
  const QList<QVariant> answer = picked.takeFirst();
  CHECK(answer.at(2).toString() == QStringLiteral("particle"));
  CHECK(answer.at(3).toLongLong() >= 0);
  // The radius is the picked particle's own, in metres, as the file holds it
  // (issue 29 saw "radius 0" reported for a 5.7 mm particle once).
  auto file = dem::DemFileReader::open(crackRoot().file("cuboidA.h5"));
  REQUIRE(file.isOk());
  const auto lattice = file->readLattice();
  REQUIRE(lattice.isOk());
  const auto index = static_cast<std::size_t>(answer.at(3).toLongLong());
  REQUIRE(index < lattice->radius.size());
  REQUIRE(lattice->radius[index] > 0.0);
  const std::string radius = fmt::format("radius {:.6g} m", lattice->radius[index]);
  INFO(answer.at(1).toString().toStdString());
  CHECK(answer.at(1).toString().contains(QString::fromStdString(radius)));
  CHECK(spinUntil([&] { return window.messages().contains(QStringLiteral("picked: particle")); },
                  5000));
  // Off the specimen (the view's corner, the background): nothing there.
  CHECK(window.viewport().pickAt(picture.topLeft() + QPoint(2, 2)));
  REQUIRE(spinUntil([&] { return picked.count() > 0; }, 10000));
  CHECK(picked.takeFirst().at(1).toString() == QStringLiteral("nothing there"));
  // Outside the picture no event is sent; the server refuses a point
  // outside the view all the same.
  CHECK_FALSE(window.viewport().pickAt(QPoint(-5, -5)));
  QSignalSpy failed(&window.client(), &client::RenderClient::eventFailed);
  window.client().pick(2.0, 0.5);
  REQUIRE(spinUntil([&] { return failed.count() > 0; }, 10000));
  CHECK(failed.takeFirst().at(1).toString().contains(QStringLiteral("fractions of the view")));
  CHECK(window.client().hasSession());
}

TEST_CASE("the step plot shows the broken bonds of every step and goes to a clicked step",
          "[client][ui][integration]") {
  application();
  auto services = startServices();
  client::MainWindow window;
  openCuboid(window, *services.render);
  const client::StepHistory& history = window.stepPlot().history();
  const int steps = window.client().stepCount();
  // The history is asked for off the window's thread and arrives later.
  REQUIRE(spinUntil([&] { return static_cast<int>(history.brokenBonds.size()) == steps; }, 10000));
  REQUIRE(static_cast<int>(history.time.size()) == steps);
  // Against the file's own bond states, step by step (the plot counts
  // /bonds/break_step).
  auto file = dem::DemFileReader::open(crackRoot().file("cuboidA.h5"));
  REQUIRE(file.isOk());
  for (const int step : {0, steps / 2, steps - 1}) {
    auto state = file->readBondState(step);
    REQUIRE(state.isOk());
    CHECK(history.brokenBonds[static_cast<std::size_t>(step)] ==
          std::count(state->begin(), state->end(), std::uint8_t{1}));
  }
  CHECK(history.brokenBonds.back() > history.brokenBonds.front());
  CHECK(history.bondCount > history.brokenBonds.back());
  CHECK(history.time.back() > history.time.front());

  // A click in the plot's middle goes to the middle step.
  const QRect area = window.stepPlot().plotArea();
  const int middle = window.stepPlot().stepAt(area.center().x());
  CHECK(std::abs(middle - (steps - 1) / 2) <= 1);
  QTest::mouseClick(&window.stepPlot(), Qt::LeftButton, Qt::NoModifier, area.center());
  // States sent before the click (the window's resize) may still be on
  // their way: the slider settles on the clicked step.
  CHECK(spinUntil(
      [&] { return window.client().step() == middle && window.stepSlider().value() == middle; },
      10000));
  // A scalar the file lacks is not drawn (the simulator's files have none).
  CHECK_FALSE(window.stepPlot().setScalar(QStringLiteral("load")));
  CHECK(window.plotScalarBox().count() == 1 + history.scalarNames.size());

  // The crack's numbers of the panel's method join the series: the crack
  // area drawn against the broken bonds, which grow to the last step.
  // The window stays responsive while the server computes them: a step
  // change goes through meanwhile.
  window.crackNumbersButton().click();
  const client::StepHistory& withCracks = window.stepPlot().history();
  CHECK_FALSE(withCracks.scalarNames.contains(QStringLiteral("total_area")));  // not yet
  window.stepSlider().setValue(steps / 3);
  REQUIRE(spinUntil([&] { return withCracks.scalarNames.contains(QStringLiteral("total_area")); },
                    60000));
  CHECK(spinUntil([&] { return window.client().step() == steps / 3; }, 10000));
  const auto areaSeries = withCracks.scalarNames.indexOf(QStringLiteral("total_area"));
  REQUIRE(areaSeries >= 0);
  const std::vector<double>& crackArea = withCracks.scalars[static_cast<std::size_t>(areaSeries)];
  REQUIRE(static_cast<int>(crackArea.size()) == steps);
  CHECK(crackArea.back() > crackArea.front());
  CHECK(window.plotScalarBox().findText(QStringLiteral("fragments")) > 0);
  window.plotScalarBox().setCurrentIndex(
      window.plotScalarBox().findText(QStringLiteral("total_area")));
  const int brokenAxis = window.plotAxisBox().findText(QStringLiteral("broken bonds"));
  REQUIRE(brokenAxis > 0);
  window.plotAxisBox().setCurrentIndex(brokenAxis);
  CHECK(window.stepPlot().axis() == QStringLiteral("broken bonds"));
  CHECK(window.stepPlot().scalar() == QStringLiteral("total_area"));
  CHECK(window.stepPlot().stepAt(area.left() + area.width()) ==
        static_cast<int>(
            std::max_element(withCracks.brokenBonds.begin(), withCracks.brokenBonds.end()) -
            withCracks.brokenBonds.begin()));
  CHECK(window.messages().contains(QStringLiteral("the Steps plot has the crack's numbers")));
}

TEST_CASE("the window follows a live file: the slider and plot grow, Follow latest, run ended",
          "[client][ui][integration][live]") {
  application();
  auto services = startServices();
  const std::string path = crackRoot().file("client-live.h5");
  std::filesystem::remove(path);
  constexpr int kSteps = 40;
  const pid_t writer =
      startProcess({CRACKVIS_CLI, "sim", "plate2d", "--scale", "0.3", "--steps",
                    std::to_string(kSteps), "--pace", "0.2", "--live", "-q", "-o", path});
  REQUIRE(spinUntil([&] { return std::filesystem::exists(path); }));
  client::MainWindow window;
  window.resize(900, 600);
  window.show();
  REQUIRE(window.connectTo(settingsFor(*services.render)));
  REQUIRE(window.openFile(QStringLiteral("client-live.h5")));
  // Opened at its last step, a live file is followed.
  REQUIRE(spinUntil([&] { return window.followButton().isChecked(); }, 10000));
  CHECK(window.followButton().isEnabled());
  const int first = window.stepSlider().maximum();
  REQUIRE(spinUntil([&] { return window.stepSlider().maximum() >= first + 3; }, 20000));
  CHECK(window.liveLabel().text().startsWith(QStringLiteral("live")));
  CHECK(window.stepSlider().value() == window.stepSlider().maximum());  // the newest step
  CHECK(spinUntil(
      [&] { return static_cast<int>(window.stepPlot().history().time.size()) > first + 1; },
      10000));  // the Steps plot grew too

  // Stepping back leaves follow mode; Follow latest returns to the newest step.
  window.stepSlider().setValue(1);
  REQUIRE(spinUntil([&] { return !window.followButton().isChecked(); }, 10000));
  const int held = window.stepSlider().maximum();
  REQUIRE(spinUntil([&] { return window.stepSlider().maximum() > held; }, 20000));
  CHECK(window.stepSlider().value() == 1);
  QTest::mouseClick(&window.followButton(), Qt::LeftButton);
  REQUIRE(spinUntil(
      [&] {
        return window.followButton().isChecked() &&
               window.stepSlider().value() == window.stepSlider().maximum();
      },
      10000));

  REQUIRE(
      spinUntil([&] { return window.liveLabel().text() == QStringLiteral("run ended"); }, 30000));
  CHECK(waitProcess(writer) == 0);
  CHECK(window.stepSlider().maximum() == kSteps - 1);
  CHECK(window.stepSlider().value() == kSteps - 1);
  CHECK_FALSE(window.followButton().isEnabled());
  window.client().closeSession();
  std::filesystem::remove(path);
}
