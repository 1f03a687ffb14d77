#include <QCheckBox>
#include <QColor>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QDoubleValidator>
#include <QFormLayout>
#include <QGroupBox>
#include <QHBoxLayout>
#include <QLabel>
#include <QLineEdit>
#include <QSpinBox>
#include <QVBoxLayout>
#include <cmath>
#include <limits>
#include <optional>

#include <crackvis/client_ui/pipeline_panel.hpp>

namespace crackvis::client {
namespace {

using namespace crackvis::pipeline;

// Combo entries carry the enum value as item data.
template <typename Enum>
QComboBox* combo(std::initializer_list<std::pair<const char*, Enum>> items) {
  auto* box = new QComboBox;
  for (const auto& [label, value] : items) {
    box->addItem(QString::fromUtf8(label), static_cast<int>(value));
  }
  return box;
}

template <typename Enum>
Enum selected(const QComboBox* box) {
  return static_cast<Enum>(box->currentData().toInt());
}

template <typename Enum>
void select(QComboBox* box, Enum value) {
  box->setCurrentIndex(box->findData(static_cast<int>(value)));
}

QDoubleSpinBox* spin(double lo, double hi, double step, int decimals) {
  auto* box = new QDoubleSpinBox;
  box->setRange(lo, hi);
  box->setSingleStep(step);
  box->setDecimals(decimals);
  return box;
}

QString hex(Colour c) {
  return QColor(c.r, c.g, c.b).name();
}

Colour colour(const QString& text, Colour otherwise) {
  const QColor parsed(text);
  if (!parsed.isValid()) {
    return otherwise;
  }
  return {static_cast<std::uint8_t>(parsed.red()), static_cast<std::uint8_t>(parsed.green()),
          static_cast<std::uint8_t>(parsed.blue())};
}

// Extra entries carry kExtra as data and the array's name as their text
// after the prefix.
const QString kExtraPrefix = QStringLiteral("extra: ");

// Replaces a colour-by box's extra entries (data `extraValue`) by `names`.
void replaceExtras(QComboBox* box, int extraValue, const QStringList& names) {
  for (int i = box->count() - 1; i >= 0; --i) {
    if (box->itemData(i).toInt() == extraValue) {
      box->removeItem(i);
    }
  }
  for (const QString& name : names) {
    box->addItem(kExtraPrefix + name, extraValue);
  }
}

// Selects `value`, or the extra entry of `extra` when value is the extra kind.
template <typename Enum>
void selectColourBy(QComboBox* box, Enum value, Enum extraValue, const std::string& extra) {
  if (value == extraValue) {
    box->setCurrentIndex(box->findText(kExtraPrefix + QString::fromStdString(extra)));
  } else {
    select(box, value);
  }
}

// The selected extra entry's name; empty unless it is the extra kind.
std::string selectedExtra(const QComboBox* box, int extraValue) {
  return box->currentData().toInt() == extraValue
             ? box->currentText().mid(kExtraPrefix.size()).toStdString()
             : std::string();
}

// A number field where empty means "none given" (an open threshold end).
QLineEdit* numberField(const QString& placeholder) {
  auto* field = new QLineEdit;
  field->setPlaceholderText(placeholder);
  field->setValidator(new QDoubleValidator(field));
  return field;
}

QString numberText(double value) {
  return std::isfinite(value) ? QString::number(value, 'g', 10) : QString();
}

// The field's number, or `otherwise` when it is empty or no number.
double numberIn(const QLineEdit* field, double otherwise) {
  bool ok = false;
  const double value = field->text().toDouble(&ok);
  return ok && std::isfinite(value) ? value : otherwise;
}

// A threshold's quantities: a layer's colour-by entries without solid.
QComboBox* quantityBox(const QComboBox* colourBy, int solidValue) {
  auto* box = new QComboBox;
  for (int i = 0; i < colourBy->count(); ++i) {
    if (colourBy->itemData(i).toInt() != solidValue) {
      box->addItem(colourBy->itemText(i), colourBy->itemData(i));
    }
  }
  return box;
}

QHBoxLayout* row(std::initializer_list<QWidget*> widgets) {
  auto* layout = new QHBoxLayout;
  for (QWidget* widget : widgets) {
    layout->addWidget(widget);
  }
  return layout;
}

// The range editor, clip switch and threshold row of one layer, added to
// `form`.
PipelinePanel::LayerControls layerControls(QFormLayout* form, const QComboBox* colourBy,
                                           int solidValue) {
  PipelinePanel::LayerControls c;
  c.rangeMode = combo<RangeMode>({{"per step", RangeMode::kStep},
                                  {"over all steps", RangeMode::kSeries},
                                  {"set", RangeMode::kUser}});
  c.rangeMin = numberField(QObject::tr("min"));
  c.rangeMax = numberField(QObject::tr("max"));
  form->addRow(QObject::tr("colour range"), row({c.rangeMode, c.rangeMin, c.rangeMax}));
  c.clip = new QCheckBox(QObject::tr("cut by the clipping plane"));
  form->addRow(c.clip);
  c.threshold = new QCheckBox(QObject::tr("threshold"));
  c.thresholdBy = quantityBox(colourBy, solidValue);
  c.thresholdMin = numberField(QObject::tr("from (open)"));
  c.thresholdMax = numberField(QObject::tr("to (open)"));
  form->addRow(row({c.threshold, c.thresholdBy, c.thresholdMin, c.thresholdMax}));
  return c;
}

template <typename Layer>
void showLayer(const PipelinePanel::LayerControls& c, const Layer& layer) {
  select(c.rangeMode, layer.range.mode);
  c.rangeMin->setText(layer.range.mode == RangeMode::kUser ? numberText(layer.range.min)
                                                           : QString());
  c.rangeMax->setText(layer.range.mode == RangeMode::kUser ? numberText(layer.range.max)
                                                           : QString());
  c.clip->setChecked(layer.clip.has_value());
  c.threshold->setChecked(layer.threshold.has_value());
  if (layer.threshold) {
    const int value = static_cast<int>(layer.threshold->by);
    int index = c.thresholdBy->findData(value);
    if (!layer.threshold->byExtra.empty()) {
      index =
          c.thresholdBy->findText(kExtraPrefix + QString::fromStdString(layer.threshold->byExtra));
    }
    c.thresholdBy->setCurrentIndex(std::max(0, index));
    c.thresholdMin->setText(numberText(layer.threshold->min));
    c.thresholdMax->setText(numberText(layer.threshold->max));
  }
}

// `extraValue`: the layer's colour-by value of an extra array (none for
// cracks: a value no entry has).
template <typename Layer>
void collectLayer(const PipelinePanel::LayerControls& c, const std::optional<ClipPlane>& plane,
                  int extraValue, Layer& layer) {
  layer.range.mode = selected<RangeMode>(c.rangeMode);
  if (layer.range.mode == RangeMode::kUser) {
    layer.range.min = numberIn(c.rangeMin, 0.0);
    layer.range.max = numberIn(c.rangeMax, layer.range.min + 1.0);
  }
  layer.clip.reset();
  if (c.clip->isChecked()) {
    layer.clip = plane;
  }
  layer.threshold.reset();
  if (c.threshold->isChecked() && c.thresholdBy->count() > 0) {
    using By = decltype(layer.threshold->by);
    Threshold<By> t;
    t.by = static_cast<By>(c.thresholdBy->currentData().toInt());
    t.byExtra = selectedExtra(c.thresholdBy, extraValue);
    t.min = numberIn(c.thresholdMin, -std::numeric_limits<double>::infinity());
    t.max = numberIn(c.thresholdMax, std::numeric_limits<double>::infinity());
    layer.threshold = t;
  }
}

}  // namespace

PipelinePanel::PipelinePanel(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);

  auto* cracks = new QGroupBox(tr("Crack surfaces"));
  auto* crackForm = new QFormLayout(cracks);
  m_cracksVisible = new QCheckBox(tr("visible"));
  m_method = combo<cracks::Method>({{"local Voronoi", cracks::Method::kLocalVoronoi},
                                    {"cell cut", cracks::Method::kCellCut},
                                    {"cell centre", cracks::Method::kCellCentre},
                                    {"cell attribute", cracks::Method::kCellAttribute}});
  m_method->setObjectName(QStringLiteral("method"));
  m_validation = new QCheckBox(tr("validate (empty-sphere test)"));
  m_tolerance = spin(0.0, 1.0, 0.05, 2);
  m_merge = new QCheckBox(tr("merge octahedra (cell centre)"));
  m_decompositionKind =
      combo<cracks::Decomposition>({{"auto", cracks::Decomposition::kAuto},
                                    {"lattice cells", cracks::Decomposition::kLattice},
                                    {"triangulation", cracks::Decomposition::kTriangulation}});
  m_decompositionKind->setObjectName(QStringLiteral("decomposition"));
  m_largest = new QSpinBox;
  m_largest->setRange(0, 1000000);
  m_largest->setSpecialValueText(tr("all"));
  m_largest->setObjectName(QStringLiteral("largest"));
  m_largest->setToolTip(tr("Show only the K largest crack components (1: the main crack)"));
  m_crackColour = combo<CrackColourBy>({{"solid", CrackColourBy::kSolid},
                                        {"bond id", CrackColourBy::kBondId},
                                        {"force", CrackColourBy::kForce},
                                        {"break step", CrackColourBy::kBreakStep},
                                        {"state", CrackColourBy::kState},
                                        {"component", CrackColourBy::kComponent},
                                        {"opening", CrackColourBy::kOpening},
                                        {"slip", CrackColourBy::kSlip}});
  m_crackOpacity = spin(0.0, 1.0, 0.1, 2);
  crackForm->addRow(m_cracksVisible);
  crackForm->addRow(tr("method"), m_method);
  crackForm->addRow(m_validation);
  crackForm->addRow(tr("tolerance"), m_tolerance);
  crackForm->addRow(m_merge);
  crackForm->addRow(tr("cells"), m_decompositionKind);
  crackForm->addRow(tr("largest components"), m_largest);
  crackForm->addRow(tr("colour by"), m_crackColour);
  crackForm->addRow(tr("opacity"), m_crackOpacity);
  m_crackLayer = layerControls(crackForm, m_crackColour, static_cast<int>(CrackColourBy::kSolid));
  layout->addWidget(cracks);

  auto* particles = new QGroupBox(tr("Particles"));
  auto* particleForm = new QFormLayout(particles);
  m_particlesVisible = new QCheckBox(tr("visible"));
  m_particleRepresentation =
      combo<ParticleRepresentation>({{"sphere impostors", ParticleRepresentation::kImpostors},
                                     {"points", ParticleRepresentation::kPoints}});
  m_particleColour = combo<ParticleColourBy>({{"solid", ParticleColourBy::kSolid},
                                              {"radius", ParticleColourBy::kRadius},
                                              {"displacement", ParticleColourBy::kDisplacement},
                                              {"velocity", ParticleColourBy::kVelocity},
                                              {"damage", ParticleColourBy::kDamage},
                                              {"fragment", ParticleColourBy::kFragment}});
  m_particleOpacity = spin(0.0, 1.0, 0.1, 2);
  auto* clipRow = new QHBoxLayout;
  for (int k = 0; k < 3; ++k) {
    m_clipOrigin[k] = spin(-1e6, 1e6, 1.0, 2);
    m_clipNormal[k] = spin(-1.0, 1.0, 0.1, 2);
  }
  for (auto* box : m_clipOrigin) {
    clipRow->addWidget(box);
  }
  auto* normalRow = new QHBoxLayout;
  for (auto* box : m_clipNormal) {
    normalRow->addWidget(box);
  }
  particleForm->addRow(m_particlesVisible);
  particleForm->addRow(tr("representation"), m_particleRepresentation);
  particleForm->addRow(tr("colour by"), m_particleColour);
  particleForm->addRow(tr("opacity"), m_particleOpacity);
  m_particleLayer =
      layerControls(particleForm, m_particleColour, static_cast<int>(ParticleColourBy::kSolid));
  layout->addWidget(particles);

  auto* bonds = new QGroupBox(tr("Bonds and decomposition"));
  auto* bondForm = new QFormLayout(bonds);
  m_bondsShow = combo<BondSelection>({{"none", BondSelection::kNone},
                                      {"broken", BondSelection::kBroken},
                                      {"all", BondSelection::kAll}});
  m_bondRepresentation = combo<BondRepresentation>(
      {{"lines", BondRepresentation::kLines}, {"tubes", BondRepresentation::kTubes}});
  m_bondColour = combo<BondColourBy>({{"state", BondColourBy::kState},
                                      {"solid", BondColourBy::kSolid},
                                      {"force", BondColourBy::kForce},
                                      {"break step", BondColourBy::kBreakStep}});
  m_tubeRadius = spin(0.01, 1.0, 0.05, 2);
  m_decomposition = new QCheckBox(tr("show the local decomposition"));
  m_inconsistent = new QCheckBox(tr("mark inconsistent bonds"));
  bondForm->addRow(tr("show"), m_bondsShow);
  bondForm->addRow(tr("as"), m_bondRepresentation);
  bondForm->addRow(tr("colour by"), m_bondColour);
  bondForm->addRow(tr("tube radius"), m_tubeRadius);
  m_bondLayer = layerControls(bondForm, m_bondColour, static_cast<int>(BondColourBy::kSolid));
  bondForm->addRow(m_decomposition);
  bondForm->addRow(m_inconsistent);
  layout->addWidget(bonds);

  auto* clip = new QGroupBox(tr("Clipping plane (hides the side the normal points to)"));
  auto* clipForm = new QFormLayout(clip);
  clipForm->addRow(tr("origin (m)"), clipRow);
  clipForm->addRow(tr("normal"), normalRow);
  clipForm->addRow(new QLabel(tr("Cuts each layer whose \"cut by the clipping plane\" is on.")));
  layout->addWidget(clip);

  auto* view = new QGroupBox(tr("View and stream"));
  auto* viewForm = new QFormLayout(view);
  m_background = new QLineEdit;
  m_colourMap = combo<ColourMap>({{"viridis", ColourMap::kViridis},
                                  {"cool to warm", ColourMap::kCoolWarm},
                                  {"rainbow", ColourMap::kRainbow},
                                  {"grayscale", ColourMap::kGrayscale}});
  m_scalarBar = new QCheckBox(tr("scalar bars"));
  m_annotations = new QCheckBox(tr("annotations (step, time, method, axes, scale bar)"));
  m_fps = new QSpinBox;
  m_fps->setRange(1, 120);
  m_bitrate = new QSpinBox;
  m_bitrate->setRange(100, 100000);
  m_bitrate->setSuffix(QStringLiteral(" kbit/s"));
  viewForm->addRow(tr("background"), m_background);
  viewForm->addRow(tr("colour map"), m_colourMap);
  viewForm->addRow(m_scalarBar);
  viewForm->addRow(m_annotations);
  viewForm->addRow(tr("stream fps"), m_fps);
  viewForm->addRow(tr("bitrate"), m_bitrate);
  layout->addWidget(view);
  layout->addStretch();

  show(m_description);
  for (auto* box : findChildren<QComboBox*>()) {
    connect(box, &QComboBox::currentIndexChanged, this, &PipelinePanel::collect);
  }
  for (auto* box : findChildren<QCheckBox*>()) {
    connect(box, &QCheckBox::toggled, this, &PipelinePanel::collect);
  }
  for (auto* box : findChildren<QDoubleSpinBox*>()) {
    connect(box, &QDoubleSpinBox::editingFinished, this, &PipelinePanel::collect);
  }
  for (auto* box : findChildren<QSpinBox*>()) {
    connect(box, &QSpinBox::editingFinished, this, &PipelinePanel::collect);
  }
  for (auto* field : findChildren<QLineEdit*>()) {
    connect(field, &QLineEdit::editingFinished, this, &PipelinePanel::collect);
  }
}

void PipelinePanel::setExtras(const QStringList& particleNames, const QStringList& bondNames) {
  m_updating = true;
  replaceExtras(m_particleColour, static_cast<int>(ParticleColourBy::kExtra), particleNames);
  replaceExtras(m_bondColour, static_cast<int>(BondColourBy::kExtra), bondNames);
  replaceExtras(m_particleLayer.thresholdBy, static_cast<int>(ParticleColourBy::kExtra),
                particleNames);
  replaceExtras(m_bondLayer.thresholdBy, static_cast<int>(BondColourBy::kExtra), bondNames);
  m_updating = false;
  show(m_description);
}

void PipelinePanel::setDescription(const pipeline::PipelineDescription& description) {
  m_description = description;
  show(description);
}

void PipelinePanel::show(const pipeline::PipelineDescription& d) {
  m_updating = true;
  m_particlesVisible->setChecked(d.particles.visible);
  select(m_particleRepresentation, d.particles.representation);
  selectColourBy(m_particleColour, d.particles.colourBy, ParticleColourBy::kExtra,
                 d.particles.colourByExtra);
  m_particleOpacity->setValue(d.particles.opacity);
  // One plane in the panel: the first layer's that has one.
  const ClipPlane clip = d.particles.clip.value_or(
      d.cracks.clip.value_or(d.bonds.clip.value_or(ClipPlane{{0, 0, 0}, {1, 0, 0}})));
  const double origin[3] = {clip.origin.x, clip.origin.y, clip.origin.z};
  const double normal[3] = {clip.normal.x, clip.normal.y, clip.normal.z};
  for (int k = 0; k < 3; ++k) {
    m_clipOrigin[k]->setValue(origin[k]);
    m_clipNormal[k]->setValue(normal[k]);
  }
  m_cracksVisible->setChecked(d.cracks.visible);
  select(m_method, d.cracks.method);
  m_validation->setChecked(d.cracks.validation);
  m_tolerance->setValue(d.cracks.validationTolerance);
  m_merge->setChecked(d.cracks.mergeOctahedra);
  select(m_decompositionKind, d.cracks.decomposition);
  m_largest->setValue(d.cracks.largest);
  select(m_crackColour, d.cracks.colourBy);
  m_crackOpacity->setValue(d.cracks.opacity);
  showLayer(m_particleLayer, d.particles);
  showLayer(m_crackLayer, d.cracks);
  showLayer(m_bondLayer, d.bonds);
  select(m_bondsShow, d.bonds.show);
  select(m_bondRepresentation, d.bonds.representation);
  selectColourBy(m_bondColour, d.bonds.colourBy, BondColourBy::kExtra, d.bonds.colourByExtra);
  m_tubeRadius->setValue(d.bonds.tubeRadius);
  m_decomposition->setChecked(d.showDecomposition);
  m_inconsistent->setChecked(d.showInconsistent);
  m_background->setText(hex(d.view.background));
  select(m_colourMap, d.view.colourMap);
  m_scalarBar->setChecked(d.view.scalarBar);
  m_annotations->setChecked(d.annotations.show);
  m_fps->setValue(d.stream.fps);
  m_bitrate->setValue(d.stream.bitrate / 1000);
  m_updating = false;
}

void PipelinePanel::collect() {
  if (m_updating) {
    return;
  }
  PipelineDescription d = m_description;
  d.particles.visible = m_particlesVisible->isChecked();
  d.particles.representation = selected<ParticleRepresentation>(m_particleRepresentation);
  d.particles.colourBy = selected<ParticleColourBy>(m_particleColour);
  d.particles.colourByExtra =
      selectedExtra(m_particleColour, static_cast<int>(ParticleColourBy::kExtra));
  d.particles.opacity = m_particleOpacity->value();
  const std::optional<ClipPlane> plane =
      ClipPlane{{m_clipOrigin[0]->value(), m_clipOrigin[1]->value(), m_clipOrigin[2]->value()},
                {m_clipNormal[0]->value(), m_clipNormal[1]->value(), m_clipNormal[2]->value()}};
  collectLayer(m_particleLayer, plane, static_cast<int>(ParticleColourBy::kExtra), d.particles);
  collectLayer(m_crackLayer, plane, -1, d.cracks);
  collectLayer(m_bondLayer, plane, static_cast<int>(BondColourBy::kExtra), d.bonds);
  d.cracks.visible = m_cracksVisible->isChecked();
  d.cracks.method = selected<cracks::Method>(m_method);
  d.cracks.validation = m_validation->isChecked();
  d.cracks.validationTolerance = m_tolerance->value();
  d.cracks.mergeOctahedra = m_merge->isChecked();
  d.cracks.decomposition = selected<cracks::Decomposition>(m_decompositionKind);
  d.cracks.largest = m_largest->value();
  d.cracks.colourBy = selected<CrackColourBy>(m_crackColour);
  d.cracks.opacity = m_crackOpacity->value();
  d.bonds.show = selected<BondSelection>(m_bondsShow);
  d.bonds.representation = selected<BondRepresentation>(m_bondRepresentation);
  d.bonds.colourBy = selected<BondColourBy>(m_bondColour);
  d.bonds.colourByExtra = selectedExtra(m_bondColour, static_cast<int>(BondColourBy::kExtra));
  d.bonds.tubeRadius = m_tubeRadius->value();
  d.showDecomposition = m_decomposition->isChecked();
  d.showInconsistent = m_inconsistent->isChecked();
  d.view.background = colour(m_background->text(), d.view.background);
  d.view.colourMap = selected<ColourMap>(m_colourMap);
  d.view.scalarBar = m_scalarBar->isChecked();
  d.annotations.show = m_annotations->isChecked();
  d.stream.fps = m_fps->value();
  d.stream.bitrate = m_bitrate->value() * 1000;
  if (d == m_description) {
    return;
  }
  m_description = d;
  emit changed(m_description);
}

}  // namespace crackvis::client
