// crackvis-client: the Qt6 thin client of crackvis-render. With --connect it
// connects at once (else File > Connect); --file opens a file.
#include <QApplication>
#include <QCommandLineParser>
#include <QFile>
#include <QTimer>

#include <crackvis/client/main_window.hpp>

int main(int argc, char** argv) {
  QApplication app(argc, argv);
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
  parser.addOptions({connect, ca, cert, key, token, file, pipelineFile, screenshot});
  parser.process(app);

  crackvis::client::MainWindow window;
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
    window.pipelinePanel().setDescription(*description);
  }
  window.show();
  if (parser.isSet(connect)) {
    const crackvis::client::ConnectionSettings settings{parser.value(connect), parser.value(ca),
                                                        parser.value(cert), parser.value(key),
                                                        parser.value(token)};
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
