// crackvis-client: the Qt6 thin client of crackvis-render. With --connect it
// connects at once (else File > Connect); --file opens a file.
#include <QApplication>
#include <QCommandLineParser>
#include <QFile>
#include <QTimer>
#include <cstdio>
#include <memory>
#include <optional>

#include <crackvis/client_core/demo_script.hpp>
#include <crackvis/client_ui/latency_run.hpp>
#include <crackvis/client_ui/main_window.hpp>
#include <crackvis/common/spelling.hpp>
#include <crackvis/rpc/connection_advice.hpp>

namespace {

constexpr int kExitFailure = 1;
constexpr int kExitUsage = 2;

// --name or --name=value among the arguments (Qt's -platform too).
bool hasArgument(int argc, char** argv, const char* name) {
  const QByteArray wanted(name);
  for (int i = 1; i < argc; ++i) {
    const QByteArray arg(argv[i]);
    if (arg == wanted || arg.startsWith(wanted + "=")) {
      return true;
    }
  }
  return false;
}

bool wantsDemo(int argc, char** argv) {
  return hasArgument(argc, argv, "--demo");
}

// Qt aborts when its platform plugin finds no display: a window needs X11
// or Wayland unless another platform (offscreen) is chosen.
bool displayMissing(int argc, char** argv) {
  const QByteArray platform = qgetenv("QT_QPA_PLATFORM");
  const bool needsDisplay =
      platform.isEmpty() || platform.startsWith("xcb") || platform.startsWith("wayland");
  return needsDisplay && !hasArgument(argc, argv, "-platform") &&
         qEnvironmentVariableIsEmpty("DISPLAY") && qEnvironmentVariableIsEmpty("WAYLAND_DISPLAY");
}

int fail(const QString& message, int code) {
  std::fprintf(stderr, "crackvis-client: %s\n", qPrintable(message));
  return code;
}

// Unknown options with the nearest known one ("unknown option '--conect'
// (did you mean --connect?)"); empty when the command line parses.
QString misspelling(const QCommandLineParser& parser, const QList<QCommandLineOption>& options) {
  const QStringList unknown = parser.unknownOptionNames();
  if (unknown.isEmpty()) {
    return parser.errorText();
  }
  std::vector<std::string> names;
  for (const QCommandLineOption& option : options) {
    for (const QString& name : option.names()) {
      names.push_back((name.size() == 1 ? "-" : "--") + name.toStdString());
    }
  }
  const QString given =
      (unknown.front().size() == 1 ? QStringLiteral("-") : QStringLiteral("--")) + unknown.front();
  const std::string nearest = crackvis::closestName(given.toStdString(), names);
  return QStringLiteral("unknown option '%1'%2")
      .arg(given, nearest.empty()
                      ? QString()
                      : QStringLiteral(" (did you mean %1?)").arg(QString::fromStdString(nearest)));
}

// --measure-latency's numbers, or nothing and what is wrong with them.
std::optional<crackvis::client::LatencyRunOptions> latencyRunOptions(const QString& size,
                                                                     const QString& seconds,
                                                                     const QString& stills,
                                                                     QString& why) {
  crackvis::client::LatencyRunOptions options;
  const QStringList sides = size.split(QLatin1Char('x'));
  bool wide = false;
  bool high = false;
  if (sides.size() == 2) {
    options.view = QSize(sides[0].toInt(&wide), sides[1].toInt(&high));
  }
  if (!wide || !high || options.view.width() < 320 || options.view.height() < 240 ||
      options.view.width() % 2 != 0 || options.view.height() % 2 != 0) {
    why = QStringLiteral("--view-size %1: expected WxH, even, at least 320x240").arg(size);
    return std::nullopt;
  }
  bool number = false;
  options.seconds = seconds.toDouble(&number);
  if (!number || !(options.seconds >= 0.5 && options.seconds <= 600.0)) {
    why = QStringLiteral("--drag-seconds %1: expected 0.5 to 600 seconds").arg(seconds);
    return std::nullopt;
  }
  options.stills = stills.toInt(&number);
  if (!number || options.stills < 0 || options.stills > 1000) {
    why = QStringLiteral("--still-moves %1: expected 0 to 1000").arg(stills);
    return std::nullopt;
  }
  return options;
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
  crackvis::rpc::quietGrpcLogs();  // a failure is the one line this program prints
  // Without a display the scripted demo (and --help) runs on a
  // QCoreApplication; a window without one would end in Qt's abort.
  const bool demo = wantsDemo(argc, argv);
  const bool help = hasArgument(argc, argv, "--help") || hasArgument(argc, argv, "-h") ||
                    hasArgument(argc, argv, "--help-all");
  if (!demo && !help && displayMissing(argc, argv)) {
    return fail(QStringLiteral("no display (DISPLAY and WAYLAND_DISPLAY are not set): run the "
                               "scripted session without a window with --demo FOLDER, or the "
                               "window off screen with QT_QPA_PLATFORM=offscreen"),
                kExitUsage);
  }
  std::unique_ptr<QCoreApplication> application =
      demo || help ? std::make_unique<QCoreApplication>(argc, argv)
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
      QStringLiteral("start from this view: a pipeline description (XML, docs/pipeline.md) as "
                     "File > Save view writes it, with its file (unless --file), step and camera"),
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
  QCommandLineOption measureLatency(
      QStringLiteral("measure-latency"),
      QStringLiteral("time the window as a user drives it, then quit: the view sized to "
                     "--view-size, a drag of rotate moves at 60 Hz for --drag-seconds, then "
                     "--still-moves still camera moves; writes each event's latency from its send "
                     "to the frame painted (p50, p95), frames per second, decode time and CPU per "
                     "frame as JSON to this file (- for standard output), as the browser page's "
                     "benchmark does (tools/bench/browser-vs-client.sh)"),
      QStringLiteral("json"));
  QCommandLineOption viewSize(QStringLiteral("view-size"),
                              QStringLiteral("the view's size for --measure-latency"),
                              QStringLiteral("WxH"), QStringLiteral("1280x720"));
  QCommandLineOption dragSeconds(QStringLiteral("drag-seconds"),
                                 QStringLiteral("the drag's length for --measure-latency"),
                                 QStringLiteral("seconds"), QStringLiteral("5"));
  QCommandLineOption stillMoves(QStringLiteral("still-moves"),
                                QStringLiteral("still camera moves for --measure-latency"),
                                QStringLiteral("count"), QStringLiteral("10"));
  const QList<QCommandLineOption> options{
      connect,        ca,       token,       file,       pipelineFile, screenshot, demoOption,
      measureLatency, viewSize, dragSeconds, stillMoves, cert,         key};
  parser.addOptions(options);
  if (!parser.parse(QCoreApplication::arguments())) {
    return fail(misspelling(parser, options), kExitUsage);
  }
  parser.process(app);  // --help

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
  if (parser.isSet(measureLatency) && (demo || parser.isSet(screenshot))) {
    return fail(QStringLiteral("--measure-latency runs the window alone: leave out %1")
                    .arg(demo ? QStringLiteral("--demo") : QStringLiteral("--window-screenshot")),
                kExitUsage);
  }
  if (demo) {
    if (!parser.isSet(connect) || !parser.isSet(file)) {
      qCritical("crackvis-client: --demo needs --connect and --file");
      return 2;
    }
    return runHeadlessDemo(settings, parser.value(file), parser.value(demoOption), startView);
  }
  // A screenshot or latency run has no one to read the messages pane: what
  // goes wrong is printed at once, and the program ends with status 1.
  const bool screenshotRun = parser.isSet(screenshot);
  const bool latencyRun = parser.isSet(measureLatency);
  crackvis::client::LatencyRunOptions latencyOptions;
  if (latencyRun) {
    QString why;
    auto parsed = latencyRunOptions(parser.value(viewSize), parser.value(dragSeconds),
                                    parser.value(stillMoves), why);
    if (!parsed) {
      return fail(why, kExitUsage);
    }
    latencyOptions = *parsed;
    latencyOptions.jsonPath = parser.value(measureLatency);
  }
  // --file, else the file a saved view (--pipeline) names.
  const QString fileToOpen =
      parser.isSet(file) ? parser.value(file) : QString::fromStdString(startView.file);
  if ((screenshotRun || latencyRun) && (!parser.isSet(connect) || fileToOpen.isEmpty())) {
    return fail(QStringLiteral("%1 needs --connect and --file (or a --pipeline view that names "
                               "a file)")
                    .arg(screenshotRun ? QStringLiteral("--window-screenshot")
                                       : QStringLiteral("--measure-latency")),
                kExitUsage);
  }

  crackvis::client::MainWindow window;
  if (parser.isSet(pipelineFile)) {
    window.pipelinePanel().setDescription(startView);
  }
  window.show();
  crackvis::client::LatencyRun* timing = nullptr;
  if (latencyRun) {
    timing = new crackvis::client::LatencyRun(window, latencyOptions);
    QObject::connect(timing, &crackvis::client::LatencyRun::finished, &window,
                     [](int code, const QString& why) {
                       if (code != 0) {
                         fail(why, code);
                       }
                       QApplication::exit(code);
                     });
    QObject::connect(&window.client(), &crackvis::client::RenderClient::eventFailed, timing,
                     [timing](quint64, const QString& message) { timing->fail(message); });
    QObject::connect(
        &window.client(), &crackvis::client::RenderClient::connectionLost, timing,
        [timing](const QString& why) { timing->fail(QStringLiteral("connection lost: ") + why); });
    timing->start();
  }
  if (parser.isSet(connect)) {
    // A saved view (--pipeline) opens as it was saved: its step (a step the
    // file lacks is the server's error, in the messages pane) and camera;
    // a file alone at its last step, the camera fitted to it.
    bool opened = window.connectTo(settings);
    if (opened && timing != nullptr) {
      timing->start();  // the first frame timed from the file's open
    }
    if (opened && !fileToOpen.isEmpty()) {
      if (parser.isSet(pipelineFile)) {
        startView.file = fileToOpen.toStdString();
        opened = window.openView(startView);
      } else {
        opened = window.openFile(fileToOpen, -1);
      }
    }
    if (!opened && (screenshotRun || latencyRun)) {
      return fail(window.lastMessage(), kExitFailure);
    }
  }
  if (screenshotRun) {
    const auto quit = [said = std::make_shared<bool>(false)](const QString& why) {
      if (!*said) {  // the first failure is the one to read
        *said = true;
        fail(why, kExitFailure);
      }
      QApplication::exit(kExitFailure);
    };
    QObject::connect(&window.client(), &crackvis::client::RenderClient::eventFailed, &window,
                     [quit](quint64, const QString& message) { quit(message); });
    QObject::connect(
        &window.client(), &crackvis::client::RenderClient::connectionLost, &window,
        [quit](const QString& why) { quit(QStringLiteral("connection lost: ") + why); });
    // Once the stream has settled (a full-resolution frame and nothing newer
    // for a second: the window's resize has gone through), grab and quit.
    const QString path = parser.value(screenshot);
    auto* settle = new QTimer(&window);
    settle->setSingleShot(true);
    settle->setInterval(1000);
    QObject::connect(settle, &QTimer::timeout, &window, [&window, path, quit] {
      if (window.grab().save(path)) {
        QApplication::exit(0);
      } else {
        quit(QStringLiteral("cannot write %1").arg(path));
      }
    });
    QObject::connect(&window.client(), &crackvis::client::RenderClient::frameReady, settle,
                     [settle](const QImage&, const crackvis::client::FrameInfo& info) {
                       if (info.fullResolution) {
                         settle->start();
                       } else {
                         settle->stop();
                       }
                     });
    QTimer::singleShot(60000, &app,
                       [quit] { quit(QStringLiteral("no full-resolution frame within 60 s")); });
  }
  return QApplication::exec();
}
