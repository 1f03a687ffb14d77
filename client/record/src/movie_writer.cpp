#include <fmt/format.h>

#include <crackvis/record/movie_writer.hpp>

namespace crackvis::record {

Result<std::unique_ptr<MovieWriter>> MovieWriter::start(const std::string& path,
                                                        const MovieSettings& settings) {
  if (settings.width % 2 != 0 || settings.height % 2 != 0 || settings.width < 16 ||
      settings.height < 16) {
    return invalidArgument(
        fmt::format("movie {}: {}x{}: H.264 (4:2:0) needs even sizes of at "
                    "least 16 pixels",
                    path, settings.width, settings.height));
  }
  std::unique_ptr<MovieWriter> writer(new MovieWriter);
  writer->m_settings = settings;
  encode::limitCodecLogsToWarnings();
  auto encoder = encode::FrameEncoder::create(
      {settings.width, settings.height, settings.fps, settings.bitrate, 20, "medium"});
  if (!encoder) {
    return encoder.status();
  }
  writer->m_encoder = std::move(encoder).value();
  auto recorder = StreamRecorder::start(path, settings.width, settings.height, settings.fps);
  if (!recorder) {
    return recorder.status();
  }
  writer->m_recorder = std::move(recorder).value();
  return writer;
}

MovieWriter::~MovieWriter() = default;

Status MovieWriter::add(const encode::RgbFrame& frame) {
  const bool keyframe = m_frames % (2 * m_settings.fps) == 0;
  auto encoded = m_encoder->encode(frame, keyframe);
  if (!encoded) {
    return encoded.status();
  }
  CRACKVIS_RETURN_IF_ERROR(
      m_recorder->add(*encoded, static_cast<double>(m_frames) / m_settings.fps));
  ++m_frames;
  return Status::ok();
}

Status MovieWriter::finish() {
  return m_recorder->finish();
}

}  // namespace crackvis::record
