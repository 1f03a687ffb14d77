#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string_view>

#include <fmt/format.h>

#include <crackvis/encode/av_support.hpp>
#include <crackvis/encode/frame_codec.hpp>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/imgutils.h>
#include <libavutil/log.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

namespace crackvis::encode {
namespace {

struct ScaleFree {
  void operator()(SwsContext* context) const { sws_freeContext(context); }
};

using Scaler = std::unique_ptr<SwsContext, ScaleFree>;

// libavcodec's allocators return null when out of memory.
Status allocated(const void* object, const char* call) {
  if (object == nullptr) {
    return Status(StatusCode::kResourceExhausted, fmt::format("{}: out of memory", call));
  }
  return Status::ok();
}

// The settings an H.264 stream can be made with: even sizes of at least 16,
// 1..240 fps, a bitrate of at least two frames' worth of 1 kbit/s.
Status checkSettings(const EncoderSettings& settings) {
  if (settings.width < 16 || settings.height < 16 || settings.width > 8192 ||
      settings.height > 8192 || settings.width % 2 != 0 || settings.height % 2 != 0) {
    return invalidArgument(fmt::format("frame size {}x{}: H.264 needs even sizes of 16..8192",
                                       settings.width, settings.height));
  }
  if (settings.fps < 1 || settings.fps > 240) {
    return invalidArgument(fmt::format("encoder fps {} outside 1..240", settings.fps));
  }
  // libx264 takes any preset string and fails only when it opens.
  static constexpr std::array<std::string_view, 10> kPresets{
      "ultrafast", "superfast", "veryfast", "faster",   "fast",
      "medium",    "slow",      "slower",   "veryslow", "placebo"};
  if (std::find(kPresets.begin(), kPresets.end(), settings.preset) == kPresets.end()) {
    return invalidArgument(fmt::format("libx264 has no preset '{}'", settings.preset));
  }
  if (settings.bitrate == 0 && (settings.crf < 0 || settings.crf > 51)) {
    return invalidArgument(fmt::format("encoder crf {} outside 0..51", settings.crf));
  }
  if (settings.bitrate != 0 && settings.bitrate < 1000 * settings.fps) {
    return invalidArgument(fmt::format("encoder bitrate {} below 1 kbit per frame ({} fps)",
                                       settings.bitrate, settings.fps));
  }
  return Status::ok();
}

Status check(int code, const char* call) {
  if (code < 0) {
    return failedPrecondition(fmt::format("{}: {}", call, avError(code)));
  }
  return Status::ok();
}

// Which source pixel each pixel of a frame `to` long shows when a line of
// `from` is enlarged by replication (render::resample's rule).
void replicationMap(int from, int to, std::vector<int>& map) {
  map.resize(static_cast<std::size_t>(to));
  for (int x = 0; x < to; ++x) {
    map[static_cast<std::size_t>(x)] = std::min(from - 1, x * from / to);
  }
}

// The luma plane of `target` from the small frame's: pixel (x, y) takes
// source pixel (column[x], row[y]). A row that shows the same source row as
// the row above it is copied from it.
void replicateLuma(const std::uint8_t* source, int sourceStride, std::uint8_t* target,
                   int targetStride, int width, int height, const std::vector<int>& column,
                   const std::vector<int>& row) {
  int previous = -1;
  for (int y = 0; y < height; ++y) {
    std::uint8_t* out = target + static_cast<std::ptrdiff_t>(y) * targetStride;
    const int sy = row[static_cast<std::size_t>(y)];
    if (sy == previous) {
      std::memcpy(out, out - targetStride, static_cast<std::size_t>(width));
      continue;
    }
    previous = sy;
    const std::uint8_t* in = source + static_cast<std::ptrdiff_t>(sy) * sourceStride;
    for (int x = 0; x < width; ++x) {
      out[x] = in[column[static_cast<std::size_t>(x)]];
    }
  }
}

// A chroma plane (4:2:0) of `target` from the small frame's 4:4:4 one: each
// sample is the mean of the 2 x 2 pixels it covers in the enlarged frame, as
// the whole frame's conversion averages them.
void replicateChroma(const std::uint8_t* source, int sourceStride, std::uint8_t* target,
                     int targetStride, int width, int height, const std::vector<int>& column,
                     const std::vector<int>& row) {
  for (int y = 0; y < height; ++y) {
    std::uint8_t* out = target + static_cast<std::ptrdiff_t>(y) * targetStride;
    const std::uint8_t* upper =
        source + static_cast<std::ptrdiff_t>(row[static_cast<std::size_t>(2 * y)]) * sourceStride;
    const std::uint8_t* lower =
        source +
        static_cast<std::ptrdiff_t>(row[static_cast<std::size_t>(2 * y + 1)]) * sourceStride;
    for (int x = 0; x < width; ++x) {
      const int left = column[static_cast<std::size_t>(2 * x)];
      const int right = column[static_cast<std::size_t>(2 * x + 1)];
      out[x] = static_cast<std::uint8_t>(
          (upper[left] + upper[right] + lower[left] + lower[right] + 2) >> 2);
    }
  }
}

}  // namespace

struct FrameEncoder::Impl {
  av::CodecContext context;
  av::Frame yuv;
  av::Packet packet;
  Scaler toYuv;
  std::int64_t next = 0;
  // A reduced frame: converted at its size to YUV 4:4:4, then replicated.
  Scaler smallToYuv;
  av::Frame small;
  std::vector<int> column;  // per pixel of the stream's width, the frame's
  std::vector<int> row;

  Status convert(const RgbFrame& frame);
  Status convertSmall(const RgbFrame& frame);
};

Result<std::unique_ptr<FrameEncoder>> FrameEncoder::create(const EncoderSettings& settings) {
  CRACKVIS_RETURN_IF_ERROR(checkSettings(settings));
  const AVCodec* codec = avcodec_find_encoder_by_name("libx264");
  if (codec == nullptr) {
    return failedPrecondition("libavcodec has no libx264 encoder (install libavcodec59 with x264)");
  }
  std::unique_ptr<FrameEncoder> encoder(new FrameEncoder());
  encoder->m_settings = settings;
  encoder->m_impl = std::make_unique<Impl>();
  Impl& impl = *encoder->m_impl;
  impl.context.reset(avcodec_alloc_context3(codec));
  CRACKVIS_RETURN_IF_ERROR(allocated(impl.context.get(), "avcodec_alloc_context3(libx264)"));
  AVCodecContext* c = impl.context.get();
  c->width = settings.width;
  c->height = settings.height;
  c->time_base = AVRational{1, settings.fps};
  c->framerate = AVRational{settings.fps, 1};
  c->pix_fmt = AV_PIX_FMT_YUV420P;
  if (settings.bitrate > 0) {
    c->bit_rate = settings.bitrate;
    c->rc_max_rate = settings.bitrate;                        // capped
    c->rc_buffer_size = settings.bitrate / settings.fps * 2;  // about two frames of VBV
  } else {
    av_opt_set_int(c->priv_data, "crf", settings.crf, 0);  // a movie: quality, not a cap
  }
  c->gop_size = 10 * settings.fps;  // keyframes come on demand
  c->max_b_frames = 0;
  c->thread_count = 2;
  av_opt_set(c->priv_data, "preset", settings.preset.c_str(), 0);
  av_opt_set(c->priv_data, "tune", "zerolatency", 0);
  CRACKVIS_RETURN_IF_ERROR(check(avcodec_open2(c, codec, nullptr), "avcodec_open2(libx264)"));
  impl.yuv.reset(av_frame_alloc());
  CRACKVIS_RETURN_IF_ERROR(allocated(impl.yuv.get(), "av_frame_alloc"));
  impl.yuv->format = c->pix_fmt;
  impl.yuv->width = c->width;
  impl.yuv->height = c->height;
  CRACKVIS_RETURN_IF_ERROR(check(av_frame_get_buffer(impl.yuv.get(), 0), "av_frame_get_buffer"));
  impl.packet.reset(av_packet_alloc());
  CRACKVIS_RETURN_IF_ERROR(allocated(impl.packet.get(), "av_packet_alloc"));
  // Same size, so the flag only picks how chroma is subsampled: point
  // sampling converts a 720p frame in 1.4 ms instead of 2.2 ms (bilinear),
  // and the round trip stays above 35 dB (tests/render/rendered_frames.test.cpp).
  impl.toYuv.reset(sws_getContext(c->width, c->height, AV_PIX_FMT_RGB24, c->width, c->height,
                                  AV_PIX_FMT_YUV420P, SWS_POINT, nullptr, nullptr, nullptr));
  if (!impl.toYuv) {
    return failedPrecondition("sws_getContext: RGB24 to YUV420P not available");
  }
  return encoder;
}

FrameEncoder::~FrameEncoder() = default;

Status FrameEncoder::Impl::convert(const RgbFrame& frame) {
  const std::uint8_t* source[1] = {frame.rgb.data()};
  const int stride[1] = {frame.width * 3};
  if (sws_scale(toYuv.get(), source, stride, 0, frame.height, yuv->data, yuv->linesize) !=
      frame.height) {
    return internalError("sws_scale: RGB24 to YUV420P converted fewer rows than the frame has");
  }
  return Status::ok();
}

Status FrameEncoder::Impl::convertSmall(const RgbFrame& frame) {
  if (!small || small->width != frame.width || small->height != frame.height) {
    // Made aside and kept only once both exist: a failure leaves no half
    // made frame for the next one of this size.
    small.reset();
    smallToYuv.reset();
    av::Frame planes(av_frame_alloc());
    CRACKVIS_RETURN_IF_ERROR(allocated(planes.get(), "av_frame_alloc"));
    planes->format = AV_PIX_FMT_YUV444P;
    planes->width = frame.width;
    planes->height = frame.height;
    CRACKVIS_RETURN_IF_ERROR(check(av_frame_get_buffer(planes.get(), 0), "av_frame_get_buffer"));
    Scaler scaler(sws_getContext(frame.width, frame.height, AV_PIX_FMT_RGB24, frame.width,
                                 frame.height, AV_PIX_FMT_YUV444P, SWS_POINT, nullptr, nullptr,
                                 nullptr));
    if (!scaler) {
      return failedPrecondition("sws_getContext: RGB24 to YUV444P not available");
    }
    replicationMap(frame.width, yuv->width, column);
    replicationMap(frame.height, yuv->height, row);
    small = std::move(planes);
    smallToYuv = std::move(scaler);
  }
  const std::uint8_t* source[1] = {frame.rgb.data()};
  const int stride[1] = {frame.width * 3};
  if (sws_scale(smallToYuv.get(), source, stride, 0, frame.height, small->data, small->linesize) !=
      frame.height) {
    return internalError("sws_scale: RGB24 to YUV444P converted fewer rows than the frame has");
  }
  replicateLuma(small->data[0], small->linesize[0], yuv->data[0], yuv->linesize[0], yuv->width,
                yuv->height, column, row);
  for (int plane = 1; plane <= 2; ++plane) {
    replicateChroma(small->data[plane], small->linesize[plane], yuv->data[plane],
                    yuv->linesize[plane], yuv->width / 2, yuv->height / 2, column, row);
  }
  return Status::ok();
}

Result<EncodedFrame> FrameEncoder::encode(const RgbFrame& frame, bool keyframe) {
  Impl& impl = *m_impl;
  if (frame.width < 1 || frame.height < 1 || frame.width > m_settings.width ||
      frame.height > m_settings.height ||
      frame.rgb.size() !=
          static_cast<std::size_t>(frame.width) * static_cast<std::size_t>(frame.height) * 3) {
    return invalidArgument(fmt::format("frame {}x{} for an encoder of {}x{}", frame.width,
                                       frame.height, m_settings.width, m_settings.height));
  }
  CRACKVIS_RETURN_IF_ERROR(check(av_frame_make_writable(impl.yuv.get()), "av_frame_make_writable"));
  const bool whole = frame.width == m_settings.width && frame.height == m_settings.height;
  CRACKVIS_RETURN_IF_ERROR(whole ? impl.convert(frame) : impl.convertSmall(frame));
  impl.yuv->pts = impl.next;
  impl.yuv->pict_type = keyframe ? AV_PICTURE_TYPE_I : AV_PICTURE_TYPE_NONE;
  impl.yuv->key_frame = keyframe ? 1 : 0;
  CRACKVIS_RETURN_IF_ERROR(
      check(avcodec_send_frame(impl.context.get(), impl.yuv.get()), "avcodec_send_frame"));
  EncodedFrame out;
  out.index = impl.next++;
  for (;;) {
    const int received = avcodec_receive_packet(impl.context.get(), impl.packet.get());
    if (received == AVERROR(EAGAIN) || received == AVERROR_EOF) {
      break;
    }
    CRACKVIS_RETURN_IF_ERROR(check(received, "avcodec_receive_packet"));
    out.data.insert(out.data.end(), impl.packet->data, impl.packet->data + impl.packet->size);
    out.keyframe = out.keyframe || (impl.packet->flags & AV_PKT_FLAG_KEY) != 0;
    av_packet_unref(impl.packet.get());
  }
  if (out.data.empty()) {
    return internalError("libx264 returned no access unit for a frame (zerolatency should)");
  }
  return out;
}

struct FrameDecoder::Impl {
  av::CodecContext context;
  av::Frame yuv;
  av::Packet packet;
  Scaler toRgb;
  int scalerWidth = 0;
  int scalerHeight = 0;
};

Result<std::unique_ptr<FrameDecoder>> FrameDecoder::create() {
  const AVCodec* codec = avcodec_find_decoder(AV_CODEC_ID_H264);
  if (codec == nullptr) {
    return failedPrecondition("libavcodec has no H.264 decoder");
  }
  std::unique_ptr<FrameDecoder> decoder(new FrameDecoder());
  decoder->m_impl = std::make_unique<Impl>();
  Impl& impl = *decoder->m_impl;
  impl.context.reset(avcodec_alloc_context3(codec));
  CRACKVIS_RETURN_IF_ERROR(allocated(impl.context.get(), "avcodec_alloc_context3(h264)"));
  impl.context->flags |= AV_CODEC_FLAG_LOW_DELAY;
  CRACKVIS_RETURN_IF_ERROR(
      check(avcodec_open2(impl.context.get(), codec, nullptr), "avcodec_open2(h264)"));
  impl.yuv.reset(av_frame_alloc());
  CRACKVIS_RETURN_IF_ERROR(allocated(impl.yuv.get(), "av_frame_alloc"));
  impl.packet.reset(av_packet_alloc());
  CRACKVIS_RETURN_IF_ERROR(allocated(impl.packet.get(), "av_packet_alloc"));
  return decoder;
}

FrameDecoder::~FrameDecoder() = default;

namespace {
constexpr std::size_t kScalerPadding = 256;
}  // namespace

Result<std::optional<RgbFrame>> FrameDecoder::decode(const EncodedFrame& frame) {
  RgbFrame picture;
  auto decoded = decodeInto(frame, picture);
  if (!decoded) {
    return decoded.status();
  }
  return *decoded ? std::optional<RgbFrame>(std::move(picture)) : std::optional<RgbFrame>{};
}

Result<bool> FrameDecoder::decodeInto(const EncodedFrame& frame, RgbFrame& picture) {
  Impl& impl = *m_impl;
  impl.packet->data = const_cast<std::uint8_t*>(frame.data.data());
  impl.packet->size = static_cast<int>(frame.data.size());
  const int sent = avcodec_send_packet(impl.context.get(), impl.packet.get());
  impl.packet->data = nullptr;
  impl.packet->size = 0;
  CRACKVIS_RETURN_IF_ERROR(check(sent, "avcodec_send_packet"));
  const int received = avcodec_receive_frame(impl.context.get(), impl.yuv.get());
  if (received == AVERROR(EAGAIN)) {
    return false;
  }
  CRACKVIS_RETURN_IF_ERROR(check(received, "avcodec_receive_frame"));
  const int width = impl.yuv->width;
  const int height = impl.yuv->height;
  if (!impl.toRgb || width != impl.scalerWidth || height != impl.scalerHeight) {
    impl.toRgb.reset(sws_getContext(width, height, static_cast<AVPixelFormat>(impl.yuv->format),
                                    width, height, AV_PIX_FMT_RGB24,
                                    SWS_BILINEAR | SWS_ACCURATE_RND | SWS_FULL_CHR_H_INT, nullptr,
                                    nullptr, nullptr));
    CRACKVIS_RETURN_IF_ERROR(allocated(impl.toRgb.get(), "sws_getContext(YUV to RGB24)"));
    impl.scalerWidth = width;
    impl.scalerHeight = height;
  }
  // swscale's special-case YUV to RGB converter works in SIMD blocks: for a
  // width that is not a multiple of 8 it wrote garbage into the last pixels
  // of each row and past the buffer (the heap corruption a 1046-pixel-wide
  // client window caused). The context above takes the generic path
  // (accurate rounding, full chroma interpolation), which handles any width;
  // the padding stays as a guard. Shrinking a vector keeps its storage, so
  // a picture decoded into again only zeroes its padding.
  // After a failure the picture holds no frame (a caller keeping the last
  // good one would otherwise show a half-converted one).
  const std::size_t bytes = static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3;
  picture.rgb.resize(bytes + kScalerPadding);
  std::uint8_t* target[1] = {picture.rgb.data()};
  const int stride[1] = {width * 3};
  const int rows =
      sws_scale(impl.toRgb.get(), impl.yuv->data, impl.yuv->linesize, 0, height, target, stride);
  av_frame_unref(impl.yuv.get());
  if (rows != height) {
    picture.width = 0;
    picture.height = 0;
    picture.rgb.clear();
    return internalError("sws_scale: YUV to RGB24 converted fewer rows than the frame has");
  }
  picture.width = width;
  picture.height = height;
  picture.rgb.resize(bytes);
  return true;
}

double psnr(const RgbFrame& a, const RgbFrame& b) {
  if (a.rgb.size() != b.rgb.size() || a.rgb.empty()) {
    return 0.0;
  }
  double sum = 0.0;
  for (std::size_t k = 0; k < a.rgb.size(); ++k) {
    const double d = static_cast<double>(a.rgb[k]) - static_cast<double>(b.rgb[k]);
    sum += d * d;
  }
  const double mse = sum / static_cast<double>(a.rgb.size());
  return mse == 0.0 ? 99.0 : 10.0 * std::log10(255.0 * 255.0 / mse);
}

std::string codecLibraryVersion() {
  const unsigned version = avcodec_version();
  return fmt::format("{}.{}.{}", AV_VERSION_MAJOR(version), AV_VERSION_MINOR(version),
                     AV_VERSION_MICRO(version));
}

void limitCodecLogsToWarnings() {
  av_log_set_level(AV_LOG_WARNING);
}

}  // namespace crackvis::encode
