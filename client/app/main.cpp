// crackvis-client: the Qt6 thin client of crackvis-render. With --connect it
// connects at once (else File > Connect); --file opens a file.
#include <QApplication>
#include <QCommandLineParser>
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
  QCommandLineOption screenshot(
      QStringLiteral("window-screenshot"),
      QStringLiteral("grab the window to this PNG once frames arrive, then quit (for docs)"),
      QStringLiteral("png"));
  parser.addOptions({connect, ca, cert, key, token, file, screenshot});
  parser.process(app);

  crackvis::client::MainWindow window;
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
    const QString path = parser.value(screenshot);
    QObject::connect(
        &window.client(), &crackvis::client::RenderClient::frameReady, &window,
        [&window, path](const QImage&, const crackvis::client::FrameInfo& info) {
          static bool scheduled = false;
          if (!scheduled && info.fullResolution && window.viewport().framesShown() > 3) {
            scheduled = true;
            QTimer::singleShot(300, &window, [&window, path] {
              window.grab().save(path);
              QApplication::quit();
            });
          }
        });
    QTimer::singleShot(60000, &app, [] { QApplication::exit(1); });
  }
  return QApplication::exec();
}
