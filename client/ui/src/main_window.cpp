#include <QAction>
#include <QApplication>
#include <QComboBox>
#include <QDataStream>
#include <QDialogButtonBox>
#include <QDockWidget>
#include <QDoubleSpinBox>
#include <QFile>
#include <QFileDialog>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QLineEdit>
#include <QMenuBar>
#include <QPlainTextEdit>
#include <QProgressDialog>
#include <QPushButton>
#include <QScrollArea>
#include <QSettings>
#include <QSlider>
#include <QSpinBox>
#include <QSplitter>
#include <QStatusBar>
#include <QTextBlock>
#include <QTextCursor>
#include <QTreeWidget>
#include <QVBoxLayout>
#include <algorithm>

#include <crackvis/client_ui/main_window.hpp>
#include <crackvis/common/pending_file.hpp>
#include <crackvis/vocabulary/crack_method.hpp>

namespace crackvis::client {

ConnectDialog::ConnectDialog(QWidget* parent) : QDialog(parent) {
  setWindowTitle(tr("Connect to crackvis-render"));
  QSettings stored;
  const ConnectionSettings defaults;
  auto field = [&](const char* key, const QString& fallback) {
    return new QLineEdit(stored.value(QString::fromUtf8(key), fallback).toString());
  };
  m_address = field("connection/address", defaults.address);
  m_ca = field("connection/ca", defaults.caPath);
  m_cert = field("connection/cert", defaults.certPath);
  m_key = field("connection/key", defaults.keyPath);
  m_token = new QLineEdit;  // secrets are not stored
  m_token->setEchoMode(QLineEdit::Password);
  auto* form = new QFormLayout(this);
  form->addRow(tr("address (host:port)"), m_address);
  form->addRow(tr("CA certificate"), m_ca);
  form->addRow(tr("client certificate"), m_cert);
  form->addRow(tr("client key"), m_key);
  form->addRow(tr("token (optional)"), m_token);
  auto* buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel);
  connect(buttons, &QDialogButtonBox::accepted, this, &QDialog::accept);
  connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
  form->addRow(buttons);
}

ConnectionSettings ConnectDialog::settings() const {
  return {m_address->text(), m_ca->text(), m_cert->text(), m_key->text(), m_token->text()};
}

void ConnectDialog::remember() const {
  QSettings stored;
  stored.setValue(QStringLiteral("connection/address"), m_address->text());
  stored.setValue(QStringLiteral("connection/ca"), m_ca->text());
  stored.setValue(QStringLiteral("connection/cert"), m_cert->text());
  stored.setValue(QStringLiteral("connection/key"), m_key->text());
}

MainWindow::MainWindow(QWidget* parent) : QMainWindow(parent) {
  setWindowTitle(QStringLiteral("crackvis"));
  m_viewport = new Viewport(m_client);
  setCentralWidget(new QWidget);
  auto* central = new QVBoxLayout(centralWidget());
  central->setContentsMargins(0, 0, 0, 0);
  central->addWidget(m_viewport, 1);
  central->addWidget(buildTimeBar());

  m_files = new QTreeWidget;
  m_files->setHeaderLabels({tr("file"), tr("size")});
  m_files->header()->setSectionResizeMode(0, QHeaderView::Stretch);
  m_description = new QPlainTextEdit;
  m_description->setReadOnly(true);
  auto* browser = new QSplitter(Qt::Vertical);
  browser->addWidget(m_files);
  browser->addWidget(m_description);
  auto* filesDock = new QDockWidget(tr("Data"), this);
  filesDock->setWidget(browser);
  addDockWidget(Qt::LeftDockWidgetArea, filesDock);

  m_panel = new PipelinePanel;
  auto* scroll = new QScrollArea;
  scroll->setWidget(m_panel);
  scroll->setWidgetResizable(true);
  auto* panelDock = new QDockWidget(tr("Pipeline"), this);
  panelDock->setWidget(scroll);
  addDockWidget(Qt::RightDockWidgetArea, panelDock);

  m_log = new QPlainTextEdit;
  m_log->setReadOnly(true);
  m_log->setMaximumBlockCount(500);
  auto* logDock = new QDockWidget(tr("Messages"), this);
  logDock->setWidget(m_log);
  addDockWidget(Qt::BottomDockWidgetArea, logDock);

  auto* stepsDock = new QDockWidget(tr("Steps"), this);
  stepsDock->setWidget(buildStepDock());
  splitDockWidget(logDock, stepsDock, Qt::Horizontal);

  m_stats = new QLabel;
  statusBar()->addPermanentWidget(m_stats);
  buildMenus();

  connect(&m_client, &RenderClient::frameReady, m_viewport, &Viewport::showFrame);
  connect(&m_client, &RenderClient::stepHistoryReady, this, &MainWindow::historyReady);
  connect(&m_client, &RenderClient::stateChanged, this, [this](int step, int steps, bool playing) {
    noteStepCount(steps);
    const QSignalBlocker blocker(m_slider);
    m_slider->setRange(0, std::max(0, steps - 1));
    m_slider->setValue(step);
    m_stepLabel->setText(tr("step %1 / %2").arg(step).arg(steps - 1));
    m_play->setText(playing ? tr("Pause") : tr("Play"));
    m_plot->setCurrentStep(step);
  });
  connect(&m_client, &RenderClient::liveChanged, this,
          [this](bool live, bool following, bool runEnded) {
            m_isLive = live;
            m_runEnded = runEnded;
            const QSignalBlocker blocker(m_follow);
            m_follow->setEnabled(live);
            m_follow->setChecked(live && following);
            updateLive();
          });
  connect(&m_client, &RenderClient::eventFailed, this,
          [this](quint64, const QString& message) { report(message); });
  connect(&m_client, &RenderClient::picked, this,
          [this](quint64, const QString& text, const QString&, qint64) {
            report(tr("picked: %1").arg(text));
          });
  // A crack method that maps few broken bonds to faces says so in the status
  // bar and the messages pane, once per cause (the numbers change with every
  // step; the cause follows the first ": ").
  connect(&m_client, &RenderClient::crackMappingChanged, this,
          [this](double, const QString& warning) {
            const QString cause = warning.section(QStringLiteral(": "), 1);
            if (!warning.isEmpty() && cause != m_lastCrackWarning) {
              report(tr("warning: %1").arg(warning));
            }
            m_lastCrackWarning = cause;
          });
  connect(&m_client, &RenderClient::connectionLost, this, [this](const QString& why) {
    report(tr("connection lost (%1); reconnecting").arg(why));
  });
  connect(&m_client, &RenderClient::reconnected, this, [this] { report(tr("reconnected")); });
  connect(m_files, &QTreeWidget::currentItemChanged, this, [this](QTreeWidgetItem* item) {
    if (item != nullptr) {
      describe(item->data(0, Qt::UserRole).toString());
    }
  });
  connect(m_files, &QTreeWidget::itemActivated, this,
          [this](QTreeWidgetItem* item) { openFile(item->data(0, Qt::UserRole).toString()); });
  connect(m_panel, &PipelinePanel::changed, this, [this](const pipeline::PipelineDescription& d) {
    if (m_client.hasSession()) {
      auto next = d;
      next.view.camera.reset();  // the panel does not move the camera
      next.file = m_file.toStdString();
      next.step = m_client.step();
      next.view.width = m_viewport->width() & ~1;
      next.view.height = m_viewport->height() & ~1;
      m_client.replacePipeline(QString::fromStdString(pipeline::toXml(next)));
    }
  });
  connect(m_viewport, &Viewport::playToggled, this, &MainWindow::togglePlay);
  connect(m_viewport, &Viewport::stepBy, this,
          [this](int delta) { m_slider->setValue(m_slider->value() + delta); });
  m_statusTimer.setInterval(500);
  connect(&m_statusTimer, &QTimer::timeout, this, &MainWindow::updateStatus);
  m_statusTimer.start();
  resize(1400, 860);
}

MainWindow::~MainWindow() {
  m_client.closeSession();
}

QWidget* MainWindow::buildStepDock() {
  auto* dock = new QWidget;
  auto* layout = new QVBoxLayout(dock);
  auto* choice = new QHBoxLayout;
  m_plotScalar = new QComboBox;
  m_plotScalar->addItem(tr("none"));
  m_plotAxis = new QComboBox;
  m_plotAxis->addItem(tr("step"));
  m_crackNumbers = new QPushButton(tr("Crack numbers"));
  m_crackNumbers->setToolTip(
      tr("Runs the panel's crack method over every step on the server and adds the crack area, "
         "main crack area, front, opening, fragments and break modes to the series (as "
         "crackvis report does): seconds for a large file"));
  choice->addWidget(new QLabel(tr("beside the broken bonds:")));
  choice->addWidget(m_plotScalar, 1);
  choice->addWidget(new QLabel(tr("against:")));
  choice->addWidget(m_plotAxis, 1);
  choice->addWidget(m_crackNumbers);
  m_plot = new StepPlot;
  layout->addLayout(choice);
  layout->addWidget(m_plot, 1);
  connect(m_plotScalar, &QComboBox::currentIndexChanged, this, [this](int index) {
    m_plot->setScalar(index > 0 ? m_plotScalar->itemText(index) : QString());
  });
  connect(m_plotAxis, &QComboBox::currentIndexChanged, this,
          [this](int index) { m_plot->setAxis(m_plotAxis->itemText(index)); });
  connect(m_crackNumbers, &QPushButton::clicked, this, &MainWindow::addCrackNumbers);
  connect(m_plot, &StepPlot::stepClicked, this, [this](int step) { m_slider->setValue(step); });
  return dock;
}

// The opened file's steps in the plot (with the crack's numbers when they
// were asked for), asked of the server off this thread: with a crack method
// it runs the method over every step, seconds for a large file, and a live
// file asks again as steps come.
void MainWindow::showHistory(const QString& file) {
  m_client.requestStepHistory(file, m_historyCracks);
}

// The series and axis chosen stay chosen when the new history has them too.
// An answer for another file than the one open now, or without the crack
// numbers asked for since, is dropped (a newer request follows it).
void MainWindow::historyReady(const QString& file, const QString& cracks,
                              const StepHistory& history, const QString& error) {
  if (file != m_file || cracks != m_historyCracks) {
    return;
  }
  if (!error.isEmpty()) {
    report(tr("no step plot for %1: %2").arg(file, error));
    m_plot->setHistory({});
    return;
  }
  const QString chosen = m_plot->scalar();
  const QString against = m_plot->axis();
  const QSignalBlocker blocker(m_plotScalar);
  const QSignalBlocker axisBlocker(m_plotAxis);
  m_plotScalar->clear();
  m_plotScalar->addItem(tr("none"));
  m_plotScalar->addItems(history.scalarNames);
  m_plot->setHistory(history);
  m_plotScalar->setCurrentIndex(std::max(0, static_cast<int>(m_plotScalar->findText(chosen))));
  m_plot->setScalar(m_plotScalar->currentIndex() > 0 ? chosen : QString());
  m_plotAxis->clear();
  m_plotAxis->addItems(m_plot->axisNames());
  m_plotAxis->setCurrentIndex(std::max(0, static_cast<int>(m_plotAxis->findText(against))));
  m_plot->setAxis(m_plotAxis->currentText());
  m_plot->setCurrentStep(m_slider->value());
  if (!cracks.isEmpty() && m_reportCrackNumbers &&
      history.scalarNames.contains(QStringLiteral("total_area"))) {
    m_reportCrackNumbers = false;
    report(tr("the Steps plot has the crack's numbers (%1): choose total_area, main_area, "
              "front_extent, fragments, ... and what to draw them against")
               .arg(cracks));
  }
}

// The crack's numbers of the panel's method over the file's steps, added
// to the plot's series when the server has computed them.
void MainWindow::addCrackNumbers() {
  if (m_file.isEmpty()) {
    report(tr("open a file first: the crack's numbers are the file's"));
    return;
  }
  m_historyCracks =
      QString::fromStdString(std::string(cracks::toString(m_panel->description().cracks.method)));
  report(tr("computing the crack's numbers (%1) over the steps of %2 ...")
             .arg(m_historyCracks, m_file));
  m_reportCrackNumbers = true;
  showHistory(m_file);
}

// A live file's step count grew: when, and the Steps plot with the new
// steps (read again at most every two seconds while steps pour in).
void MainWindow::noteStepCount(int steps) {
  if (steps > m_knownSteps && m_knownSteps > 0) {
    m_sinceLastStep.restart();
    if (!m_sincePlot.isValid() || m_sincePlot.elapsed() >= 2000) {
      m_sincePlot.restart();
      showHistory(m_file);
    }
  }
  m_knownSteps = steps;
}

void MainWindow::updateLive() {
  if (m_isLive) {
    const qint64 ago = m_sinceLastStep.isValid() ? m_sinceLastStep.elapsed() / 1000 : -1;
    m_live->setText(ago < 0 ? tr("live") : tr("live: last step %1 s ago").arg(ago));
  } else {
    m_live->setText(m_runEnded ? tr("run ended") : QString());
  }
}

QWidget* MainWindow::buildTimeBar() {
  auto* bar = new QWidget;
  auto* layout = new QHBoxLayout(bar);
  m_play = new QPushButton(tr("Play"));
  m_slider = new QSlider(Qt::Horizontal);
  m_slider->setObjectName(QStringLiteral("step"));
  m_fps = new QDoubleSpinBox;
  m_fps->setRange(0.5, 60.0);
  m_fps->setValue(10.0);
  m_fps->setSuffix(tr(" steps/s"));
  m_stepLabel = new QLabel(tr("no session"));
  m_follow = new QPushButton(tr("Follow latest"));
  m_follow->setObjectName(QStringLiteral("follow"));
  m_follow->setCheckable(true);
  m_follow->setEnabled(false);
  m_follow->setToolTip(
      tr("A live file (a run still writing it): show each new step as it "
         "arrives. Moving the slider or playing stops following."));
  m_live = new QLabel;
  m_live->setObjectName(QStringLiteral("live"));
  layout->addWidget(m_play);
  layout->addWidget(m_slider, 1);
  layout->addWidget(m_stepLabel);
  layout->addWidget(m_follow);
  layout->addWidget(m_live);
  layout->addWidget(m_fps);
  connect(m_play, &QPushButton::clicked, this, &MainWindow::togglePlay);
  connect(m_follow, &QPushButton::toggled, this, [this](bool on) {
    if (!m_client.hasSession()) {
      return;
    }
    if (on) {
      m_client.follow();
    } else {
      m_client.setStep(m_slider->value());
    }
  });
  connect(m_slider, &QSlider::valueChanged, this, [this](int step) {
    if (m_client.hasSession()) {
      m_client.setStep(step);
      m_stepLabel->setText(tr("step %1 / %2").arg(step).arg(m_client.stepCount() - 1));
    }
  });
  return bar;
}

void MainWindow::buildMenus() {
  auto* file = menuBar()->addMenu(tr("&File"));
  file->addAction(tr("&Connect..."), this, &MainWindow::showConnectDialog);
  file->addAction(tr("&Open view..."), this, &MainWindow::openViewDialog);
  file->addAction(tr("Save &view..."), this, &MainWindow::saveViewDialog);
  file->addSeparator();
  file->addAction(tr("&Screenshot (rendered on the server, any size)..."), this,
                  &MainWindow::showScreenshotDialog);
  m_recordAction =
      file->addAction(tr("&Record the stream to MP4..."), this, [this] { toggleRecording(); });
  file->addAction(tr("Record a full-resolution &movie of steps..."), this,
                  &MainWindow::showMovieDialog);
  file->addSeparator();
  file->addAction(tr("&Quit"), this, &QWidget::close);
  auto* view = menuBar()->addMenu(tr("&View"));
  view->addAction(tr("&Fit the whole specimen (r)"), this, [this] { m_client.resetCamera(); });
  view->addAction(tr("&Play / pause (space)"), this, &MainWindow::togglePlay);
}

QString MainWindow::messages() const {
  return m_log->toPlainText();
}

// A message that repeats the last one (a failing step while playing, a
// reconnect loop) replaces its line with a count instead of flooding the
// pane.
void MainWindow::report(const QString& message) {
  statusBar()->showMessage(message, 10000);
  if (message == m_lastMessage && !m_log->document()->isEmpty()) {
    ++m_lastMessageRepeats;
    QTextCursor cursor(m_log->document());
    cursor.movePosition(QTextCursor::End);
    cursor.movePosition(QTextCursor::StartOfBlock, QTextCursor::KeepAnchor);
    cursor.insertText(tr("%1 (%2 times)").arg(message).arg(m_lastMessageRepeats + 1));
    return;
  }
  m_lastMessage = message;
  m_lastMessageRepeats = 0;
  m_log->appendPlainText(message);
}

bool MainWindow::connectTo(const ConnectionSettings& settings) {
  if (Status status = m_client.connectTo(settings); !status) {
    report(tr("cannot connect: %1").arg(QString::fromStdString(status.message())));
    return false;
  }
  auto files = m_client.listFiles();
  if (!files) {
    report(QString::fromStdString(files.status().message()));
    return false;
  }
  m_files->clear();
  for (const FileEntry& entry : *files) {
    auto* item = new QTreeWidgetItem(
        m_files, {entry.path, QStringLiteral("%1 MB").arg(
                                  static_cast<double>(entry.sizeBytes) / 1e6, 0, 'f', 1)});
    item->setData(0, Qt::UserRole, entry.path);
    item->setDisabled(!entry.isHdf5);
  }
  report(tr("connected to %1: %2 files").arg(settings.address).arg(files->size()));
  return true;
}

void MainWindow::describe(const QString& file) {
  auto summary = m_client.describe(file);
  if (!summary) {
    m_description->setPlainText(QString::fromStdString(summary.status().message()));
    return;
  }
  QString text =
      tr("%1\nformat %2, %3 MB\nN = %4 particles, M = %5 bonds\n%6 steps, t = %7 .. %8 s\n\n")
          .arg(summary->file,
               summary->format.isEmpty() ? tr("(not crackvis-dem)") : summary->format)
          .arg(static_cast<double>(summary->sizeBytes) / 1e6, 0, 'f', 1)
          .arg(summary->particles)
          .arg(summary->bonds)
          .arg(summary->steps)
          .arg(summary->firstTime)
          .arg(summary->lastTime);
  text += summary->arrays.join(QLatin1Char('\n'));
  m_description->setPlainText(text);
  m_panel->setExtras(summary->particleExtras, summary->bondExtras);
}

bool MainWindow::openFile(const QString& file) {
  return openFile(file, -1);
}

bool MainWindow::openFile(const QString& file, std::int64_t step) {
  auto view = m_panel->description();
  view.file = file.toStdString();
  view.step = step;
  view.view.camera.reset();  // fitted to this file, not where the last one was seen from
  return openView(view);
}

bool MainWindow::openView(const pipeline::PipelineDescription& view) {
  const QString file = QString::fromStdString(view.file);
  describe(file);  // the file's extra arrays for the colour-by list
  auto d = view;
  // An extra array of the previous file that this one lacks: back to the default.
  const QString prefix = QStringLiteral("extra: ");
  if (d.particles.colourBy == pipeline::ParticleColourBy::kExtra &&
      m_panel->particleColourBox()->findText(
          prefix + QString::fromStdString(d.particles.colourByExtra)) < 0) {
    d.particles.colourBy = pipeline::ParticleColourBy::kSolid;
    d.particles.colourByExtra.clear();
  }
  if (d.bonds.colourBy == pipeline::BondColourBy::kExtra &&
      m_panel->bondColourBox()->findText(prefix + QString::fromStdString(d.bonds.colourByExtra)) <
          0) {
    d.bonds.colourBy = pipeline::BondColourBy::kState;
    d.bonds.colourByExtra.clear();
  }
  m_panel->setDescription(d);
  d.view.width = std::max(16, m_viewport->width() & ~1);
  d.view.height = std::max(16, m_viewport->height() & ~1);
  if (Status status = m_client.openSession(QString::fromStdString(pipeline::toXml(d))); !status) {
    report(tr("cannot open %1: %2").arg(file, QString::fromStdString(status.message())));
    return false;
  }
  if (file != m_file) {
    m_historyCracks.clear();  // another file's crack numbers are asked for anew
  }
  m_file = file;
  m_knownSteps = m_client.stepCount();
  m_sinceLastStep.invalidate();
  const QSignalBlocker blocker(m_slider);
  m_slider->setRange(0, std::max(0, m_client.stepCount() - 1));
  m_slider->setValue(d.step >= 0 ? static_cast<int>(d.step) : m_client.stepCount() - 1);
  m_stepLabel->setText(tr("step %1 / %2").arg(m_slider->value()).arg(m_client.stepCount() - 1));
  setWindowTitle(tr("crackvis - %1").arg(file));
  report(tr("opened %1 (%2 steps)").arg(file).arg(m_client.stepCount()));
  showHistory(file);
  m_viewport->setFocus();
  return true;
}

namespace {

// The window's docks and size as one base64 string (<client layout>).
std::string layoutOf(const QMainWindow& window) {
  QByteArray bytes;
  QDataStream out(&bytes, QIODevice::WriteOnly);
  out << window.saveGeometry() << window.saveState();
  return bytes.toBase64().toStdString();
}

void restoreLayout(QMainWindow& window, const std::string& layout) {
  QByteArray bytes = QByteArray::fromBase64(QByteArray::fromStdString(layout));
  QDataStream in(&bytes, QIODevice::ReadOnly);
  QByteArray geometry;
  QByteArray state;
  in >> geometry >> state;
  if (in.status() == QDataStream::Ok) {
    window.restoreGeometry(geometry);
    window.restoreState(state);
  }
}

}  // namespace

bool MainWindow::loadView(const QString& path) {
  QFile in(path);
  if (!in.open(QIODevice::ReadOnly)) {
    report(tr("cannot read the view %1: %2").arg(path, in.errorString()));
    return false;
  }
  auto view = pipeline::parsePipeline(in.readAll().toStdString());
  if (!view) {
    report(tr("%1 is no view: %2").arg(path, QString::fromStdString(view.status().message())));
    return false;
  }
  if (!view->clientLayout.empty()) {
    restoreLayout(*this, view->clientLayout);
  }
  if (!m_client.connected() || view->file.empty()) {
    m_panel->setDescription(*view);  // shown now, used by the next file opened
    report(tr("loaded the view %1 (no file opened: %2)")
               .arg(path, m_client.connected() ? tr("it names none") : tr("not connected")));
    return true;
  }
  return openView(*view);
}

bool MainWindow::saveView(const QString& path) {
  // The server's state holds what is shown (step, size, the camera where
  // the user left it); a view needs a file, so nothing is saved before one
  // is open.
  if (!m_client.hasSession()) {
    report(tr("no view to save: open a file first"));
    return false;
  }
  auto shown = pipeline::parsePipeline(m_client.pipelineXml().toStdString());
  if (!shown) {
    report(tr("cannot save the view: %1").arg(QString::fromStdString(shown.status().message())));
    return false;
  }
  pipeline::PipelineDescription view = *shown;
  view.clientLayout = layoutOf(*this);
  // Written beside the name and renamed over it when complete: a full disk
  // leaves an existing view as it was. (Qt 6.4's QSaveFile::commit returned
  // true after a write had failed with ENOSPC, leaving an empty file.)
  if (const Status written = replaceFile(path.toStdString(), pipeline::toXml(view)); !written) {
    report(tr("cannot write %1: %2").arg(path, QString::fromStdString(written.message())));
    return false;
  }
  report(tr("saved the view to %1").arg(path));
  return true;
}

void MainWindow::openViewDialog() {
  const QString path = QFileDialog::getOpenFileName(this, tr("Open view"), QString(),
                                                    tr("Pipeline description (*.xml)"));
  if (!path.isEmpty()) {
    loadView(path);
  }
}

void MainWindow::saveViewDialog() {
  const QString path = QFileDialog::getSaveFileName(
      this, tr("Save view"), QStringLiteral("view.xml"), tr("Pipeline description (*.xml)"));
  if (!path.isEmpty()) {
    saveView(path);
  }
}

void MainWindow::showConnectDialog() {
  ConnectDialog dialog(this);
  if (dialog.exec() == QDialog::Accepted && connectTo(dialog.settings())) {
    dialog.remember();
  }
}

namespace {

// Even sizes (H.264's 4:2:0 and the server's rule), up to the server's
// largest view.
QSpinBox* sizeBox(int value, int most) {
  auto* box = new QSpinBox;
  box->setRange(16, most);
  box->setSingleStep(2);
  box->setValue(std::clamp(value & ~1, 16, most));
  box->setSuffix(QStringLiteral(" px"));
  return box;
}

QDialogButtonBox* okCancel(QDialog* dialog) {
  auto* buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel);
  QObject::connect(buttons, &QDialogButtonBox::accepted, dialog, &QDialog::accept);
  QObject::connect(buttons, &QDialogButtonBox::rejected, dialog, &QDialog::reject);
  return buttons;
}

}  // namespace

QSize MainWindow::streamSize() const {
  const QSize size = m_client.frameSize();
  return size.isEmpty() ? QSize(m_viewport->width() & ~1, m_viewport->height() & ~1) : size;
}

void MainWindow::showScreenshotDialog() {
  if (!m_client.hasSession()) {
    report(tr("no view to take a screenshot of: open a file first"));
    return;
  }
  QDialog dialog(this);
  dialog.setWindowTitle(tr("Screenshot"));
  auto* form = new QFormLayout(&dialog);
  auto* width = sizeBox(streamSize().width(), 3840);
  auto* height = sizeBox(streamSize().height(), 2160);
  form->addRow(tr("width"), width);
  form->addRow(tr("height"), height);
  form->addRow(new QLabel(tr("Rendered by the server at this size, full resolution.")));
  form->addRow(okCancel(&dialog));
  if (dialog.exec() != QDialog::Accepted) {
    return;
  }
  const QString path = QFileDialog::getSaveFileName(this, tr("Screenshot"),
                                                    QStringLiteral("view.png"), tr("PNG (*.png)"));
  if (!path.isEmpty()) {
    saveScreenshot(path, QSize(width->value(), height->value()));
  }
}

void MainWindow::saveScreenshot(const QString& given, QSize size) {
  const QString path =
      given.isEmpty() ? QFileDialog::getSaveFileName(this, tr("Screenshot"),
                                                     QStringLiteral("view.png"), tr("PNG (*.png)"))
                      : given;
  if (path.isEmpty()) {
    return;
  }
  auto png = m_client.snapshotPng(size.width(), size.height());
  if (!png) {
    report(QString::fromStdString(png.status().message()));
    return;
  }
  if (const Status written =
          replaceFile(path.toStdString(), std::string_view(png->constData(), png->size()));
      !written) {
    report(tr("cannot write %1: %2").arg(path, QString::fromStdString(written.message())));
    return;
  }
  report(tr("wrote %1").arg(path));
}

void MainWindow::toggleRecording(const QString& given) {
  if (m_client.recording()) {
    const Status status = m_client.stopRecording();
    m_recordAction->setText(tr("&Record the stream to MP4..."));
    report(status ? tr("recording stopped: %1 frames").arg(m_client.recordedFrames())
                  : QString::fromStdString(status.message()));
    return;
  }
  const QString path = given.isEmpty()
                           ? QFileDialog::getSaveFileName(
                                 this, tr("Record"), QStringLiteral("view.mp4"), tr("MP4 (*.mp4)"))
                           : given;
  if (path.isEmpty()) {
    return;
  }
  const Status status = m_client.startRecording(path);
  if (status) {
    m_recordAction->setText(tr("Stop &recording"));
  }
  report(status ? tr("recording the stream to %1").arg(path)
                : QString::fromStdString(status.message()));
}

void MainWindow::showMovieDialog() {
  if (!m_client.hasSession()) {
    report(tr("no view to record: open a file first"));
    return;
  }
  const int lastStep = std::max(0, m_client.stepCount() - 1);
  QDialog dialog(this);
  dialog.setWindowTitle(tr("Full-resolution movie"));
  auto* form = new QFormLayout(&dialog);
  auto stepBox = [lastStep](int value) {
    auto* box = new QSpinBox;
    box->setRange(0, lastStep);
    box->setValue(value);
    return box;
  };
  auto* first = stepBox(0);
  auto* last = stepBox(lastStep);
  auto* stride = new QSpinBox;
  stride->setRange(1, std::max(1, lastStep));
  auto* width = sizeBox(streamSize().width(), 3840);
  auto* height = sizeBox(streamSize().height(), 2160);
  auto* fps = new QSpinBox;
  fps->setRange(1, 120);
  fps->setValue(30);
  form->addRow(tr("first step"), first);
  form->addRow(tr("last step"), last);
  form->addRow(tr("every k-th step"), stride);
  form->addRow(tr("width"), width);
  form->addRow(tr("height"), height);
  form->addRow(tr("frames per second"), fps);
  form->addRow(
      new QLabel(tr("Every frame is rendered again on the server at full resolution\n"
                    "(the stream's reduced interactive frames are not used).")));
  form->addRow(okCancel(&dialog));
  if (dialog.exec() != QDialog::Accepted) {
    return;
  }
  const QString path = QFileDialog::getSaveFileName(this, tr("Movie"), QStringLiteral("movie.mp4"),
                                                    tr("MP4 (*.mp4)"));
  if (!path.isEmpty()) {
    recordMovie(path, first->value(), last->value(), stride->value(),
                QSize(width->value(), height->value()), fps->value());
  }
}

bool MainWindow::recordMovie(const QString& path, int first, int last, int stride, QSize size,
                             int fps) {
  std::vector<int> steps;
  for (int step = first; step <= last; step += std::max(1, stride)) {
    steps.push_back(step);
  }
  if (size.isEmpty()) {
    size = streamSize();
  }
  QProgressDialog progress(tr("Rendering %1 frames on the server...").arg(steps.size()),
                           tr("Cancel"), 0, static_cast<int>(steps.size()), this);
  progress.setWindowModality(Qt::WindowModal);
  progress.setMinimumDuration(500);
  const Status status = m_client.recordMovie(path, steps, size.width() & ~1, size.height() & ~1,
                                             fps, [&progress](int done, int) {
                                               progress.setValue(done);
                                               return !progress.wasCanceled();
                                             });
  if (!status) {
    report(QString::fromStdString(status.message()));
    return false;
  }
  report(tr("wrote %1: %2 full-resolution frames at %3x%4, steps %5..%6")
             .arg(path)
             .arg(steps.size())
             .arg(size.width() & ~1)
             .arg(size.height() & ~1)
             .arg(first)
             .arg(steps.empty() ? first : steps.back()));
  return true;
}

void MainWindow::togglePlay() {
  if (m_client.hasSession()) {
    m_client.play(!m_client.playing(), m_fps->value());
  }
}

void MainWindow::updateStatus() {
  updateLive();
  const StreamStatistics stats = m_client.statistics();
  // The latency the user sees: from an event's send to the frame painted
  // (the decode and the paint included), as the browser page reports it.
  const double painted = m_viewport->paintLatencyMs();
  m_stats->setText(tr("%1 fps   latency %2 ms   %3 Mbit/s%4")
                       .arg(stats.fps, 0, 'f', 0)
                       .arg(painted >= 0.0 ? painted : stats.latencyMs, 0, 'f', 0)
                       .arg(stats.bitrateBps / 1e6, 0, 'f', 2)
                       .arg(m_client.recording() ? tr("   REC") : QString()));
}

}  // namespace crackvis::client
