// crackvis-client: the Qt6 thin client of crackvis-render. With --connect it
// connects at once (else File > Connect); --file opens a file.
#include <QApplication>
#include <QCommandLineParser>
#include <QFile>
#include <QTimer>
#include <cstdio>
#include <memory>

#include <crackvis/client/demo_script.hpp>
#include <crackvis/client/main_window.hpp>

namespace {

bool wantsDemo(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (QByteArray(argv[i]) == "--demo" || QByteArray(argv[i]).startsWith("--demo=")) {
      return true;
    }
  }
  return false;
}

// The scripted session without a window (no display needed).
int runHeadlessDemo(const crackvis::client::ConnectionSettings& settings, const QString& file,
                    const QString& outDir, const crackvis::pipeline::PipelineDescription& view) {
  crackvis::client::RenderClient client;
  auto say = [](const QString& line) {
    std::printf("crackvis-client: %s\n", qPrintable(line));
    std::fflush(stdout);
  };
  if (auto status = client.connectTo(settings); !status) {
    say(QString::fromStdString(status.message()));
    return 1;
  }
  crackvis::client::DemoOptions options;
  options.file = file;
  options.view = view;
  options.moviePath = outDir + QStringLiteral("/demo.mp4");
  options.picturePath = outDir + QStringLiteral("/demo.png");
  if (qEnvironmentVariableIsSet("CRACKVIS_DEMO_SHORT")) {  // the test's shortened run
    options.rotateEvents = 15;
    options.stepStride = 100;
  }
  auto result = crackvis::client::runDemo(client, options, say);
  if (!result) {
    say(QStringLiteral("demo failed: %1").arg(QString::fromStdString(result.status().message())));
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Without a display the scripted demo runs on a QCoreApplication.
  const bool demo = wantsDemo(argc, argv);
  std::unique_ptr<QCoreApplication> application =
      demo ? std::make_unique<QCoreApplication>(argc, argv)
           : std::make_unique<QApplication>(argc, argv);
  QCoreApplication& app = *application;
  QApplication::setOrganizationName(QStringLiteral("crackvis"));
  QApplication::setApplicationName(QStringLiteral("crackvis-client"));
  QCommandLineParser parser;
  parser.setApplicationDescription(QStringLiteral(
      "Thin client of crackvis-render: browse the data, build the pipeline, watch and steer "
      "the H.264 stream. Mouse: left rotate, middle or shift+left pan, wheel or right zoom; "
      "keys: r reset camera, space play/pause, arrows step."));
  parser.addHelpOption();
  const crackvis::client::ConnectionSettings defaults;
  QCommandLineOption connect(QStringLiteral("connect"), QStringLiteral("render server host:port"),
                             QStringLiteral("address"));
  QCommandLineOption ca(QStringLiteral("ca"), QStringLiteral("CA certificate (PEM)"),
                        QStringLiteral("file"), defaults.caPath);
  QCommandLineOption cert(QStringLiteral("cert"), QStringLiteral("client certificate (PEM)"),
                          QStringLiteral("file"), defaults.certPath);
  QCommandLineOption key(QStringLiteral("key"), QStringLiteral("client key (PEM)"),
                         QStringLiteral("file"), defaults.keyPath);
  QCommandLineOption token(QStringLiteral("token"), QStringLiteral("bearer token"),
                           QStringLiteral("token"));
  QCommandLineOption file(QStringLiteral("file"), QStringLiteral("file to open"),
                          QStringLiteral("path"));
  QCommandLineOption pipelineFile(
      QStringLiteral("pipeline"),
      QStringLiteral("start from this pipeline description (XML, pipeline-schemas/pipeline.xsd)"),
      QStringLiteral("xml"));
  QCommandLineOption screenshot(
      QStringLiteral("window-screenshot"),
      QStringLiteral("grab the window to this PNG once frames arrive, then quit (for docs)"),
      QStringLiteral("png"));
  QCommandLineOption demoOption(
      QStringLiteral("demo"),
      QStringLiteral("no window: run the scripted demo session (rotate, step through the fracture, "
                     "the four methods) and write demo.mp4 and demo.png into this folder"),
      QStringLiteral("folder"));
  parser.addOptions({connect, ca, cert, key, token, file, pipelineFile, screenshot, demoOption});
  parser.process(app);

  crackvis::pipeline::PipelineDescription startView;
  if (parser.isSet(pipelineFile)) {
    QFile xml(parser.value(pipelineFile));
    if (!xml.open(QIODevice::ReadOnly)) {
      qCritical("crackvis-client: cannot read %s", qPrintable(parser.value(pipelineFile)));
      return 1;
    }
    auto description = crackvis::pipeline::parsePipeline(xml.readAll().toStdString());
    if (!description) {
      qCritical("crackvis-client: %s: %s", qPrintable(parser.value(pipelineFile)),
                description.status().message().c_str());
      return 1;
    }
    startView = *description;
  }
  const crackvis::client::ConnectionSettings settings{parser.value(connect), parser.value(ca),
                                                      parser.value(cert), parser.value(key),
                                                      parser.value(token)};
  if (demo) {
    if (!parser.isSet(connect) || !parser.isSet(file)) {
      qCritical("crackvis-client: --demo needs --connect and --file");
      return 2;
    }
    return runHeadlessDemo(settings, parser.value(file), parser.value(demoOption), startView);
  }

  crackvis::client::MainWindow window;
  if (parser.isSet(pipelineFile)) {
    window.pipelinePanel().setDescription(startView);
  }
  window.show();
  if (parser.isSet(connect)) {
    if (window.connectTo(settings) && parser.isSet(file)) {
      window.openFile(parser.value(file));
    }
  }
  if (parser.isSet(screenshot)) {
    // Once the stream has settled (a full-resolution frame and nothing newer
    // for a second: the window's resize has gone through), grab and quit.
    const QString path = parser.value(screenshot);
    auto* settle = new QTimer(&window);
    settle->setSingleShot(true);
    settle->setInterval(1000);
    QObject::connect(settle, &QTimer::timeout, &window, [&window, path] {
      const bool saved = window.grab().save(path);
      QApplication::exit(saved ? 0 : 1);
    });
    QObject::connect(&window.client(), &crackvis::client::RenderClient::frameReady, settle,
                     [settle](const QImage&, const crackvis::client::FrameInfo& info) {
                       if (info.fullResolution) {
                         settle->start();
                       } else {
                         settle->stop();
                       }
                     });
    QTimer::singleShot(60000, &app, [] { QApplication::exit(1); });
  }
  return QApplication::exec();
}
