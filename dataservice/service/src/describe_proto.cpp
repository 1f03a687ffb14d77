#include "describe_proto.hpp"

#include <crackvis/common/utf8.hpp>

namespace crackvis::dataservice {
namespace v1 = crackvis::v1;

v1::DataType toProto(DataType type) {
  return static_cast<v1::DataType>(static_cast<int>(type));
}

namespace {

void toProto(const AttributeInfo& in, v1::Attribute& out) {
  out.set_name(toValidUtf8(in.name));
  out.set_dtype(toProto(in.dtype));
  for (auto d : in.shape) {
    out.add_shape(d);
  }
  out.set_truncated(in.truncated);
  if (const auto* text = std::get_if<std::string>(&in.value)) {
    out.set_text(toValidUtf8(*text));
  } else if (const auto* integers = std::get_if<std::vector<std::int64_t>>(&in.value)) {
    out.mutable_integers()->mutable_values()->Add(integers->begin(), integers->end());
  } else if (const auto* floats = std::get_if<std::vector<double>>(&in.value)) {
    out.mutable_floats()->mutable_values()->Add(floats->begin(), floats->end());
  }
}

}  // namespace

// Names and texts from a file may be any bytes (a corrupt file); proto3
// strings must be UTF-8 or the answer cannot be parsed, so invalid bytes
// become U+FFFD.
void toProto(const FileDescription& in, v1::DescribeResponse& out) {
  out.set_file(toValidUtf8(in.file));
  out.set_size_bytes(in.sizeBytes);
  for (const GroupInfo& group : in.groups) {
    v1::Group* g = out.add_groups();
    g->set_path(toValidUtf8(group.path));
    for (const AttributeInfo& attribute : group.attributes) {
      toProto(attribute, *g->add_attributes());
    }
  }
  for (const DatasetInfo& dataset : in.datasets) {
    v1::Dataset* d = out.add_datasets();
    d->set_path(toValidUtf8(dataset.path));
    d->set_dtype(toProto(dataset.dtype));
    d->set_dtype_name(toValidUtf8(dataset.dtypeName));
    d->mutable_shape()->Add(dataset.shape.begin(), dataset.shape.end());
    d->mutable_chunk_shape()->Add(dataset.chunkShape.begin(), dataset.chunkShape.end());
    for (const AttributeInfo& attribute : dataset.attributes) {
      toProto(attribute, *d->add_attributes());
    }
  }
  out.set_format(toValidUtf8(in.format));
  out.set_format_version(in.formatVersion);
  for (const StepEntry& step : in.steps) {
    v1::Step* s = out.add_steps();
    s->set_index(step.index);
    s->set_time(step.time);
    s->set_group(toValidUtf8(step.group));
  }
}

}  // namespace crackvis::dataservice
