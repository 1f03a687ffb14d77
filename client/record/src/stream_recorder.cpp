#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <span>
#include <vector>

#include <fmt/format.h>

#include <crackvis/common/pending_file.hpp>
#include <crackvis/encode/av_support.hpp>
#include <crackvis/record/stream_recorder.hpp>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/dict.h>
#include <libavutil/mathematics.h>
}

namespace crackvis::record {
namespace {

// 90 kHz: the MPEG clock, fine enough that times from a network receiver
// keep their jitter instead of being rounded onto a frame grid.
constexpr AVRational kClock{1, 90000};
constexpr int kSpsType = 7;
constexpr int kPpsType = 8;

using encode::avError;

struct FormatFree {
  void operator()(AVFormatContext* context) const {
    if (context->pb != nullptr) {
      avio_closep(&context->pb);
    }
    avformat_free_context(context);
  }
};

using FormatContext = std::unique_ptr<AVFormatContext, FormatFree>;

Status avFailure(const std::string& path, const char* what, int code) {
  return failedPrecondition(fmt::format("recording {}: {}: {}", path, what, avError(code)));
}

// An unwritable path is the user's mistake; the code says which one.
Status openFailure(const std::string& path, int code) {
  const std::string message =
      fmt::format("recording {}: cannot open the file for writing: {}", path, avError(code));
  if (code == AVERROR(ENOENT)) {
    return notFound(message);
  }
  if (code == AVERROR(EACCES) || code == AVERROR(EPERM)) {
    return {StatusCode::kPermissionDenied, message};
  }
  return failedPrecondition(message);
}

// The NAL units of an Annex B access unit, without their start codes (and
// without the zero bytes that pad a unit before a four-byte start code).
std::vector<std::span<const std::uint8_t>> nalUnits(std::span<const std::uint8_t> data) {
  std::vector<std::span<const std::uint8_t>> units;
  std::size_t begin = 0;
  bool inUnit = false;
  auto close = [&](std::size_t end) {
    while (end > begin && data[end - 1] == 0) {
      --end;
    }
    if (inUnit && end > begin) {
      units.push_back(data.subspan(begin, end - begin));
    }
  };
  for (std::size_t k = 0; k + 2 < data.size(); ++k) {
    if (data[k] == 0 && data[k + 1] == 0 && data[k + 2] == 1) {
      close(k);
      begin = k + 3;
      inUnit = true;
      k += 2;
    }
  }
  close(data.size());
  return units;
}

// The SPS and PPS of a keyframe, in Annex B: the mp4 muxer turns such
// extradata into the avcC box and converts every packet to length prefixes.
std::vector<std::uint8_t> parameterSets(std::span<const std::uint8_t> accessUnit) {
  constexpr std::uint8_t kStartCode[] = {0, 0, 0, 1};
  std::vector<std::uint8_t> sets;
  for (const auto unit : nalUnits(accessUnit)) {
    const int type = unit[0] & 0x1f;
    if (type == kSpsType || type == kPpsType) {
      sets.insert(sets.end(), std::begin(kStartCode), std::end(kStartCode));
      sets.insert(sets.end(), unit.begin(), unit.end());
    }
  }
  return sets;
}

}  // namespace

struct StreamRecorder::Impl {
  FormatContext format;
  AVStream* stream = nullptr;  // owned by format
  // libavcodec's H.264 parser reads each frame's size from the active SPS;
  // it needs a codec context to keep that state in.
  encode::av::CodecContext parserContext;
  encode::av::Parser parser;
  encode::av::Packet packet;
  // The recording is written beside its name and renamed over it only when
  // complete: an existing file survives a failed or empty recording.
  std::unique_ptr<PendingFile> output;
  bool opened = false;  // the file is ours: only then may finish() write or remove it
  bool headerWritten = false;
  bool finished = false;
  Status finishStatus;
  double origin = 0.0;  // `seconds` of the first keyframe: the file's time 0
  std::int64_t lastPts = AV_NOPTS_VALUE;
};

Result<std::unique_ptr<StreamRecorder>> StreamRecorder::start(const std::string& path, int width,
                                                              int height, int fps) {
  if (width <= 0 || height <= 0 || fps <= 0) {
    return invalidArgument(
        fmt::format("recording {}: size {}x{} at {} fps is not a video", path, width, height, fps));
  }
  std::unique_ptr<StreamRecorder> recorder(new StreamRecorder());
  recorder->m_path = path;
  recorder->m_width = width;
  recorder->m_height = height;
  recorder->m_fps = fps;
  recorder->m_impl = std::make_unique<Impl>();
  Impl& impl = *recorder->m_impl;
  AVFormatContext* format = nullptr;
  // The partial file's name is the muxer's URL too: moving the index to the
  // front (faststart) opens the file again by it.
  impl.output = std::make_unique<PendingFile>(path);
  // "mp4" by name: the container does not depend on the file's extension.
  const int allocated =
      avformat_alloc_output_context2(&format, nullptr, "mp4", impl.output->path().c_str());
  if (allocated < 0) {
    return avFailure(path, "avformat_alloc_output_context2(mp4)", allocated);
  }
  impl.format.reset(format);
  impl.stream = avformat_new_stream(format, nullptr);
  if (impl.stream == nullptr) {
    return internalError(fmt::format("recording {}: avformat_new_stream failed", path));
  }
  AVCodecParameters* parameters = impl.stream->codecpar;
  parameters->codec_type = AVMEDIA_TYPE_VIDEO;
  parameters->codec_id = AV_CODEC_ID_H264;
  parameters->width = width;
  parameters->height = height;
  impl.stream->time_base = kClock;
  impl.stream->avg_frame_rate = AVRational{fps, 1};
  // Opened now, so an unwritable path fails here and not at the first frame.
  const int openCode = avio_open(&format->pb, impl.output->path().c_str(), AVIO_FLAG_WRITE);
  if (openCode < 0) {
    return openFailure(path, openCode);
  }
  impl.opened = true;
  impl.parserContext.reset(avcodec_alloc_context3(nullptr));
  impl.parser.reset(av_parser_init(AV_CODEC_ID_H264));
  impl.packet.reset(av_packet_alloc());
  if (!impl.parserContext || !impl.parser || !impl.packet) {
    return internalError(fmt::format("recording {}: out of memory for the H.264 parser", path));
  }
  impl.parser->flags |= PARSER_FLAG_COMPLETE_FRAMES;  // one access unit per add()
  return recorder;
}

StreamRecorder::~StreamRecorder() {
  // A recorder that start() gave up on never opened the file: leave it be.
  if (m_impl && m_impl->opened) {
    (void)finish();
  }
}

Status StreamRecorder::add(const encode::EncodedFrame& frame, double seconds) {
  Impl& impl = *m_impl;
  if (impl.finished) {
    return failedPrecondition(
        fmt::format("recording {}: frame {} added after finish()", m_path, frame.index));
  }
  if (!impl.headerWritten && !frame.keyframe) {
    ++m_skipped;  // undecodable without the frames it refers to
    return Status::ok();
  }
  if (frame.data.empty() || !std::isfinite(seconds)) {
    return invalidArgument(fmt::format("recording {}: frame {} is empty or has no time {}", m_path,
                                       frame.index, seconds));
  }
  CRACKVIS_RETURN_IF_ERROR(loadPacket(frame));
  CRACKVIS_RETURN_IF_ERROR(checkSize(frame));
  if (!impl.headerWritten) {
    CRACKVIS_RETURN_IF_ERROR(writeHeader(frame, seconds));
  }
  return writePacket(frame, seconds);
}

// The packet owns a padded copy: the parser and the muxer may read past the end.
Status StreamRecorder::loadPacket(const encode::EncodedFrame& frame) {
  AVPacket* packet = m_impl->packet.get();
  av_packet_unref(packet);
  const int created = av_new_packet(packet, static_cast<int>(frame.data.size()));
  if (created < 0) {
    return avFailure(m_path, "av_new_packet", created);
  }
  std::memcpy(packet->data, frame.data.data(), frame.data.size());
  return Status::ok();
}

// A resize on the server starts a new stream; it cannot go on in this file,
// whose track has one size.
Status StreamRecorder::checkSize(const encode::EncodedFrame& frame) {
  Impl& impl = *m_impl;
  std::uint8_t* parsed = nullptr;
  int parsedSize = 0;
  av_parser_parse2(impl.parser.get(), impl.parserContext.get(), &parsed, &parsedSize,
                   impl.packet->data, impl.packet->size, AV_NOPTS_VALUE, AV_NOPTS_VALUE, 0);
  const int width = impl.parser->width;
  const int height = impl.parser->height;
  if (width <= 0 || height <= 0) {
    return invalidArgument(fmt::format("recording {}: frame {} has no SPS to read its size from",
                                       m_path, frame.index));
  }
  if (width != m_width || height != m_height) {
    return invalidArgument(fmt::format("recording {}: frame {} is {}x{}, the recording is {}x{}",
                                       m_path, frame.index, width, height, m_width, m_height));
  }
  return Status::ok();
}

Status StreamRecorder::writeHeader(const encode::EncodedFrame& keyframe, double seconds) {
  Impl& impl = *m_impl;
  const std::vector<std::uint8_t> sets = parameterSets(keyframe.data);
  if (sets.empty()) {
    return invalidArgument(
        fmt::format("recording {}: keyframe {} carries no SPS/PPS", m_path, keyframe.index));
  }
  AVCodecParameters* parameters = impl.stream->codecpar;
  parameters->extradata =
      static_cast<std::uint8_t*>(av_mallocz(sets.size() + AV_INPUT_BUFFER_PADDING_SIZE));
  if (parameters->extradata == nullptr) {
    return internalError(fmt::format("recording {}: out of memory for the extradata", m_path));
  }
  std::memcpy(parameters->extradata, sets.data(), sets.size());
  parameters->extradata_size = static_cast<int>(sets.size());
  // The index goes before the media so that players can start at once.
  AVDictionary* options = nullptr;
  av_dict_set(&options, "movflags", "+faststart", 0);
  const int written = avformat_write_header(impl.format.get(), &options);
  av_dict_free(&options);
  if (written < 0) {
    return avFailure(m_path, "avformat_write_header", written);
  }
  impl.headerWritten = true;
  impl.origin = seconds;
  return Status::ok();
}

Status StreamRecorder::writePacket(const encode::EncodedFrame& frame, double seconds) {
  Impl& impl = *m_impl;
  // The muxer may have chosen another time base than kClock in the header.
  const AVRational timeBase = impl.stream->time_base;
  std::int64_t pts =
      av_rescale_q(std::llround((seconds - impl.origin) * kClock.den), kClock, timeBase);
  // MP4 needs strictly increasing times; a repeated or late time from the
  // network moves one tick past the previous frame.
  if (impl.lastPts != AV_NOPTS_VALUE && pts <= impl.lastPts) {
    pts = impl.lastPts + 1;
  }
  AVPacket* packet = impl.packet.get();
  packet->pts = pts;
  packet->dts = pts;  // no B-frames in the stream (zerolatency)
  packet->duration = av_rescale_q(1, AVRational{1, m_fps}, timeBase);
  packet->stream_index = impl.stream->index;
  packet->flags = frame.keyframe ? AV_PKT_FLAG_KEY : 0;
  const int written = av_write_frame(impl.format.get(), packet);
  av_packet_unref(packet);
  if (written < 0) {
    return avFailure(m_path, "av_write_frame", written);
  }
  impl.lastPts = pts;
  ++m_written;
  return Status::ok();
}

Status StreamRecorder::finish() {
  Impl& impl = *m_impl;
  if (!impl.finished) {
    impl.finished = true;
    impl.finishStatus = closeFile();
  }
  return impl.finishStatus;
}

Status StreamRecorder::closeFile() {
  Impl& impl = *m_impl;
  Status status;
  if (impl.headerWritten) {
    const int trailer = av_write_trailer(impl.format.get());
    if (trailer < 0) {
      status = avFailure(m_path, "av_write_trailer", trailer);
    }
  }
  const int closed = avio_closep(&impl.format->pb);
  if (closed < 0 && status.isOk()) {
    status = avFailure(m_path, "avio_close", closed);
  }
  if (!impl.headerWritten) {
    // An empty file that no player opens would only mislead: the partial
    // file goes (PendingFile) and the name is left as it was.
    status = failedPrecondition(fmt::format(
        "recording {}: no keyframe arrived ({} frames skipped); nothing recorded, file removed",
        m_path, m_skipped));
  }
  if (status) {
    status = impl.output->commit();
  }
  return status;
}

}  // namespace crackvis::record
