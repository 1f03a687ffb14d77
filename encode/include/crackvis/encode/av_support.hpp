// The FFmpeg helpers that crackvis::encode (frame_codec.cpp) and
// crackvis::record (stream_recorder.cpp) share: av_strerror text for an
// AVERROR code, and unique_ptr owners for the libavcodec handles.
//
// Include it only from a target that links libavcodec and libavutil itself
// (crackvis_encode through PkgConfig::FFMPEG, crackvis_record through
// PkgConfig::RECORD_FFMPEG): crackvis::encode links FFmpeg privately, so its
// users do not get FFmpeg's include paths from it. Owners of libswscale and
// libavformat handles stay with the one library that links each, so that
// neither library needs the other's FFmpeg part.
#pragma once

#include <memory>
#include <string>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/error.h>
#include <libavutil/frame.h>
}

namespace crackvis::encode {

// The text FFmpeg gives for a negative return code. av_err2str is a
// compound literal, which C++ does not have.
inline std::string avError(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, text, sizeof text);
  return text;
}

namespace av {

struct CodecContextFree {
  void operator()(AVCodecContext* context) const { avcodec_free_context(&context); }
};
struct FrameFree {
  void operator()(AVFrame* frame) const { av_frame_free(&frame); }
};
struct PacketFree {
  void operator()(AVPacket* packet) const { av_packet_free(&packet); }
};
struct ParserFree {
  void operator()(AVCodecParserContext* parser) const { av_parser_close(parser); }
};

using CodecContext = std::unique_ptr<AVCodecContext, CodecContextFree>;
using Frame = std::unique_ptr<AVFrame, FrameFree>;
using Packet = std::unique_ptr<AVPacket, PacketFree>;
using Parser = std::unique_ptr<AVCodecParserContext, ParserFree>;

}  // namespace av
}  // namespace crackvis::encode
