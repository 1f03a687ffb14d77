// What an Image becomes besides a video frame: another size (resample) or a
// PNG (writePng, encodePng).
#include <algorithm>
#include <cstring>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkUnsignedCharArray.h>

#include "vtk_errors.hpp"
#include <crackvis/common/pending_file.hpp>
#include <crackvis/render/scene_renderer.hpp>

namespace crackvis::render {

void resample(const Image& in, int width, int height, Image& out) {
  out.width = width;
  out.height = height;
  // Capacity beyond the pixels: swscale reads RGB rows in whole SIMD blocks.
  out.rgb.reserve(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3 + 256);
  out.rgb.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3);
  std::vector<int> sourceX(static_cast<std::size_t>(width));
  for (int x = 0; x < width; ++x) {
    sourceX[static_cast<std::size_t>(x)] = std::min(in.width - 1, x * in.width / width);
  }
  for (int y = 0; y < height; ++y) {
    const int sy = std::min(in.height - 1, y * in.height / height);
    const std::uint8_t* source = in.pixel(0, sy);
    std::uint8_t* target = out.rgb.data() + static_cast<std::size_t>(y) * width * 3;
    for (int x = 0; x < width; ++x) {
      std::memcpy(target + 3 * x, source + 3 * sourceX[static_cast<std::size_t>(x)], 3);
    }
  }
}

namespace {

// VTK's images run bottom to top.
vtkSmartPointer<vtkImageData> toImageData(const Image& image) {
  auto data = vtkSmartPointer<vtkImageData>::New();
  data->SetDimensions(image.width, image.height, 1);
  data->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* target = static_cast<std::uint8_t*>(data->GetScalarPointer());
  const std::size_t row = static_cast<std::size_t>(image.width) * 3;
  for (int y = 0; y < image.height; ++y) {
    std::memcpy(target + static_cast<std::size_t>(y) * row,
                image.rgb.data() + static_cast<std::size_t>(image.height - 1 - y) * row, row);
  }
  return data;
}

}  // namespace

Status writePng(const Image& image, const std::string& path) {
  // Encoded in memory and written beside its name, renamed over it when
  // complete: a full disk leaves an existing picture as it was, and libpng
  // never writes (nor prints its write errors) itself.
  auto png = encodePng(image);
  if (!png) {
    return png.status();
  }
  return replaceFile(path,
                     std::string_view(reinterpret_cast<const char*>(png->data()), png->size()));
}

Result<std::vector<std::uint8_t>> encodePng(const Image& image) {
  if (image.width < 1 || image.height < 1) {
    return invalidArgument("an empty image has no PNG");
  }
  const VtkErrorScope vtkErrors;
  vtkNew<vtkPNGWriter> writer;
  writer->WriteToMemoryOn();
  writer->SetInputData(toImageData(image));
  writer->Write();
  vtkUnsignedCharArray* bytes = writer->GetResult();
  if (const Status vtk = vtkErrors.status("vtkPNGWriter");
      writer->GetErrorCode() != 0 || bytes == nullptr || !vtk) {
    return internalError(
        fmt::format("the PNG encoder failed ({})", vtk ? "no detail from VTK" : vtk.message()));
  }
  const auto* first = bytes->GetPointer(0);
  return std::vector<std::uint8_t>(first, first + bytes->GetNumberOfValues());
}

}  // namespace crackvis::render
