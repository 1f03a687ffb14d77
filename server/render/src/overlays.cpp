#include "overlays.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <vtkCamera.h>
#include <vtkCaptionActor2D.h>
#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkPoints.h>
#include <vtkPolyDataMapper2D.h>
#include <vtkProperty2D.h>
#include <vtkTextProperty.h>

namespace crackvis::render {
namespace {

// Fonts follow the frame's height, so a reduced frame looks like the full
// one scaled, and a 4K snapshot is not written in 720p's letters.
int fontSize(int height) {
  return std::max(9, static_cast<int>(std::lround(0.022 * height)));
}

// The strip's share of the width: about 0.28 of the height in pixels, at
// most a fifth of the width. Depends on the aspect only, so reduced frames
// keep the full frame's layout.
double stripShare(int width, int height) {
  return std::min(0.2, 0.28 * height / std::max(1, width));
}

void styleText(vtkTextProperty* text, double lightness, int size) {
  text->SetColor(lightness, lightness, lightness);
  text->SetFontSize(size);
  text->ShadowOff();
  text->ItalicOff();
  text->BoldOff();
  text->SetFontFamilyToArial();
}

}  // namespace

Overlays::Overlays(vtkRenderWindow* window, vtkRenderer* scene) : m_scene(scene) {
  m_legends = vtkSmartPointer<vtkRenderer>::New();
  m_legends->InteractiveOff();
  m_legends->SetViewport(1.0, 0.0, 1.0, 1.0);
  window->AddRenderer(m_legends);
  // The triad is drawn over the scene's corner: a layer above it that does
  // not clear the scene's pixels.
  window->SetNumberOfLayers(2);
  m_triad = vtkSmartPointer<vtkRenderer>::New();
  m_triad->SetLayer(1);
  m_triad->InteractiveOff();
  m_triad->DrawOff();
  window->AddRenderer(m_triad);
  m_axes = vtkSmartPointer<vtkAxesActor>::New();
  m_axes->SetShaftTypeToCylinder();
  m_axes->SetTotalLength(1.0, 1.0, 1.0);
  m_axes->SetCylinderRadius(0.04);
  m_axes->SetConeRadius(0.35);
  m_triad->AddActor(m_axes);
}

std::mutex& Overlays::textMutex() {
  static std::mutex mutex;
  return mutex;
}

void Overlays::setScene(const pipeline::PipelineDescription& d, const scene::SceneInput& input,
                        std::vector<Legend> legends) {
  const auto& bg = d.view.background;
  m_textLightness = (0.299 * bg.r + 0.587 * bg.g + 0.114 * bg.b) / 255.0 > 0.5 ? 0.0 : 1.0;
  m_legends->RemoveAllViewProps();
  m_legends->SetBackground(bg.r / 255.0, bg.g / 255.0, bg.b / 255.0);
  m_bars.clear();
  m_texts.clear();
  m_scaleLine = nullptr;
  m_scaleText = nullptr;
  m_legendsShown = d.view.scalarBar ? std::move(legends) : std::vector<Legend>{};
  addScalarBars(d);
  addAnnotations(d, input);
  m_laidOutWidth = 0;
  layout(d.view.width, d.view.height);
}

void Overlays::addScalarBars(const pipeline::PipelineDescription& d) {
  (void)d;
  for (const Legend& legend : m_legendsShown) {
    auto bar = vtkSmartPointer<vtkScalarBarActor>::New();
    bar->SetLookupTable(legend.table);
    bar->SetTitle(legend.quantity.title.c_str());
    bar->SetOrientationToVertical();
    bar->UnconstrainedFontSizeOn();
    bar->SetBarRatio(0.22);
    bar->SetDrawTickLabels(true);
    bar->SetUseCustomLabels(true);
    for (vtkTextProperty* text : {bar->GetTitleTextProperty(), bar->GetLabelTextProperty()}) {
      styleText(text, m_textLightness, 12);
    }
    m_legends->AddActor2D(bar);
    m_bars.push_back(bar);
  }
}

void Overlays::addAnnotations(const pipeline::PipelineDescription& d,
                              const scene::SceneInput& input) {
  const auto& a = d.annotations;
  m_triad->SetDraw(a.show && a.axes);
  if (!a.show) {
    return;
  }
  std::vector<std::string> lines;
  if (a.time) {
    lines.push_back(scene::stepAnnotation(input));
  }
  if (a.method) {
    lines.push_back(scene::methodAnnotation(d.cracks));
  }
  for (const std::string& line : lines) {
    if (line.empty()) {
      continue;
    }
    auto text = vtkSmartPointer<vtkTextActor>::New();
    text->SetInput(line.c_str());
    text->SetTextScaleModeToNone();
    styleText(text->GetTextProperty(), m_textLightness, 12);
    m_scene->AddActor2D(text);
    m_texts.push_back(text);
  }
  for (vtkCaptionActor2D* caption :
       {m_axes->GetXAxisCaptionActor2D(), m_axes->GetYAxisCaptionActor2D(),
        m_axes->GetZAxisCaptionActor2D()}) {
    caption->GetTextActor()->SetTextScaleModeToNone();
    styleText(caption->GetCaptionTextProperty(), m_textLightness, 12);
  }
  if (a.scaleBar) {
    m_scaleLineData = vtkSmartPointer<vtkPolyData>::New();
    vtkNew<vtkPoints> points;
    points->SetNumberOfPoints(2);
    m_scaleLineData->SetPoints(points);
    vtkNew<vtkCellArray> line;
    const vtkIdType ends[2] = {0, 1};
    line->InsertNextCell(2, ends);
    m_scaleLineData->SetLines(line);
    vtkNew<vtkPolyDataMapper2D> mapper;
    mapper->SetInputData(m_scaleLineData);
    m_scaleLine = vtkSmartPointer<vtkActor2D>::New();
    m_scaleLine->SetMapper(mapper);
    m_scaleLine->GetProperty()->SetColor(m_textLightness, m_textLightness, m_textLightness);
    m_scene->AddActor2D(m_scaleLine);
    m_scaleText = vtkSmartPointer<vtkTextActor>::New();
    m_scaleText->SetTextScaleModeToNone();
    styleText(m_scaleText->GetTextProperty(), m_textLightness, 12);
    m_scaleText->GetTextProperty()->SetJustificationToCentered();
    m_scene->AddActor2D(m_scaleText);
  }
}

void Overlays::layout(int width, int height) {
  // The scale bar and the triad follow the camera every frame; the rest
  // only the frame's size (re-laying out text re-rasterizes it).
  if (m_triad->GetDraw()) {
    layoutTriad(width, height);
  }
  if (m_scaleLine != nullptr) {
    layoutScaleBar(static_cast<int>((1.0 - m_strip) * width), height, fontSize(height));
  }
  if (width == m_laidOutWidth && height == m_laidOutHeight) {
    return;
  }
  m_laidOutWidth = width;
  m_laidOutHeight = height;
  m_strip = m_bars.empty() ? 0.0 : stripShare(width, height);
  m_scene->SetViewport(0.0, 0.0, 1.0 - m_strip, 1.0);
  m_legends->SetViewport(1.0 - m_strip, 0.0, 1.0, 1.0);
  m_legends->SetDraw(!m_bars.empty());
  const int font = fontSize(height);
  // The bars one above the other, each in its own slot with its title.
  const auto n = static_cast<double>(m_bars.size());
  for (std::size_t k = 0; k < m_bars.size(); ++k) {
    vtkScalarBarActor* bar = m_bars[k];
    const double slot = 1.0 / n;
    const double bottom = 1.0 - (static_cast<double>(k) + 1.0) * slot;
    bar->SetPosition(0.06, bottom + 0.06 * slot);
    bar->SetPosition2(0.9, slot * 0.88);
    bar->SetMaximumWidthInPixels(std::max(16, static_cast<int>(m_strip * width)));
    // Arial's letters average about 0.55 of the font size: the title's lines
    // stay within the strip.
    const auto titleChars =
        static_cast<std::size_t>(std::max(8.0, 0.9 * m_strip * width / (0.55 * fontSize(height))));
    bar->SetTitle(scene::wrapTitle(m_legendsShown[k].quantity.title, titleChars).c_str());
    bar->SetVerticalTitleSeparation(std::max(2, font / 2));
    bar->SetTextPad(std::max(1, font / 4));
    for (vtkTextProperty* text : {bar->GetTitleTextProperty(), bar->GetLabelTextProperty()}) {
      text->SetFontSize(font);
    }
    // As many labels as fit the slot with room between them.
    const double slotPixels = slot * 0.88 * height - 2.5 * font;
    const int count = std::clamp(static_cast<int>(slotPixels / (2.2 * font)), 2, 6);
    const Legend& legend = m_legendsShown[k];
    const scene::LegendTicks ticks =
        scene::legendTicks(legend.range, legend.quantity.integral, count);
    vtkNew<vtkDoubleArray> labels;
    for (double v : ticks.values) {
      labels->InsertNextValue(v);
    }
    bar->SetCustomLabels(labels);
    bar->SetLabelFormat(ticks.format.c_str());
  }
  const double sceneWidth = (1.0 - m_strip) * width;
  const double margin = std::max(3.0, 0.5 * font);
  for (std::size_t i = 0; i < m_texts.size(); ++i) {
    m_texts[i]->GetTextProperty()->SetFontSize(font);
    m_texts[i]->SetPosition(margin, height - margin - (static_cast<double>(i) + 1.0) * 1.35 * font);
  }
  if (m_triad->GetDraw()) {
    for (vtkCaptionActor2D* caption :
         {m_axes->GetXAxisCaptionActor2D(), m_axes->GetYAxisCaptionActor2D(),
          m_axes->GetZAxisCaptionActor2D()}) {
      caption->GetCaptionTextProperty()->SetFontSize(font);
    }
    layoutTriad(width, height);
  }
  if (m_scaleLine != nullptr) {
    layoutScaleBar(static_cast<int>(sceneWidth), height, font);
  }
}

// The triad in the scene's lower left corner, turned as the scene's camera.
void Overlays::layoutTriad(int width, int height) {
  const double sceneWidth = (1.0 - m_strip) * width;
  const double side = std::min(0.18 * height, 0.3 * sceneWidth);
  m_triad->SetViewport(0.0, 0.0, side / width, side / height);
  vtkCamera* main = m_scene->GetActiveCamera();
  vtkCamera* camera = m_triad->GetActiveCamera();
  double direction[3];
  main->GetDirectionOfProjection(direction);
  camera->SetFocalPoint(0.0, 0.0, 0.0);
  camera->SetPosition(-4.5 * direction[0], -4.5 * direction[1], -4.5 * direction[2]);
  camera->SetViewUp(main->GetViewUp());
  camera->SetViewAngle(30.0);
  camera->ParallelProjectionOff();
  m_triad->ResetCameraClippingRange();
}

// A round length at the focal plane, at most a fifth of the scene's width,
// at its lower right with its label above.
void Overlays::layoutScaleBar(int sceneWidth, int height, int font) {
  vtkCamera* camera = m_scene->GetActiveCamera();
  const double viewHeight = camera->GetParallelProjection() != 0
                                ? 2.0 * camera->GetParallelScale()
                                : 2.0 * camera->GetDistance() *
                                      std::tan(camera->GetViewAngle() * std::numbers::pi / 360.0);
  const scene::ScaleBar bar = scene::scaleBar(viewHeight / std::max(1, height), 0.2 * sceneWidth);
  const double margin = std::max(3.0, 0.8 * font);
  const double right = sceneWidth - margin;
  const double y = margin;
  m_scaleLineData->GetPoints()->SetPoint(0, right - bar.pixels, y, 0.0);
  m_scaleLineData->GetPoints()->SetPoint(1, right, y, 0.0);
  m_scaleLineData->GetPoints()->Modified();
  m_scaleLineData->Modified();
  m_scaleLine->GetProperty()->SetLineWidth(static_cast<float>(std::max(1.0, font / 6.0)));
  m_scaleLine->SetVisibility(bar.pixels > 0.0);
  m_scaleText->SetInput(bar.label.c_str());
  m_scaleText->GetTextProperty()->SetFontSize(font);
  m_scaleText->SetPosition(right - bar.pixels / 2.0, y + 0.4 * font);
  m_scaleText->SetVisibility(bar.pixels > 0.0);
}

}  // namespace crackvis::render
