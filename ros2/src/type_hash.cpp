// SPDX-License-Identifier: Apache-2.0
#include "sim/ros2/type_hash.hpp"

#include <algorithm>
#include <array>
#include <map>
#include <set>
#include <span>

#include "sha256.hpp"

namespace sim::ros2 {

namespace {

// type_description_interfaces/msg/FieldType ids. A fixed array adds 48, an unbounded sequence 144.
enum FieldTypeId : int {
  nested = 1, uint8 = 3, int32 = 6, uint32 = 7, float64 = 11, boolean = 15, byte_ = 16,
  string = 17, bounded_string = 21,
};
constexpr int array_of(int id) { return id + 48; }
constexpr int sequence_of(int id) { return id + 144; }

struct FieldDescription {
  std::string_view name;
  int type_id;
  int capacity = 0;         // length of a fixed array
  int string_capacity = 0;  // bound of a bounded string
  std::string_view nested_type = {};
};

struct TypeDescription {
  std::string_view name;
  std::span<const FieldDescription> fields;
};

constexpr std::string_view time_t_ = "builtin_interfaces/msg/Time";
constexpr std::string_view header_t = "std_msgs/msg/Header";
constexpr std::string_view point_field_t = "sensor_msgs/msg/PointField";
constexpr std::string_view roi_t = "sensor_msgs/msg/RegionOfInterest";
constexpr std::string_view vector3_t = "geometry_msgs/msg/Vector3";
constexpr std::string_view quaternion_t = "geometry_msgs/msg/Quaternion";
constexpr std::string_view transform_t = "geometry_msgs/msg/Transform";
constexpr std::string_view transform_stamped_t = "geometry_msgs/msg/TransformStamped";
constexpr std::string_view gid_t = "rmw_dds_common/msg/Gid";
constexpr std::string_view node_entities_t = "rmw_dds_common/msg/NodeEntitiesInfo";
constexpr std::string_view key_value_t = "diagnostic_msgs/msg/KeyValue";
constexpr std::string_view diagnostic_status_t = "diagnostic_msgs/msg/DiagnosticStatus";

// The fields of each type as its .msg file declares them (common_interfaces, geometry2,
// rmw_dds_common); default values do not enter the hash.
constexpr FieldDescription time_fields[] = {{"sec", int32}, {"nanosec", uint32}};
constexpr FieldDescription header_fields[] = {{"stamp", nested, 0, 0, time_t_},
                                              {"frame_id", string}};
constexpr FieldDescription image_fields[] = {
    {"header", nested, 0, 0, header_t}, {"height", uint32}, {"width", uint32},
    {"encoding", string}, {"is_bigendian", uint8}, {"step", uint32},
    {"data", sequence_of(uint8)}};
constexpr FieldDescription compressed_image_fields[] = {
    {"header", nested, 0, 0, header_t}, {"format", string}, {"data", sequence_of(uint8)}};
constexpr FieldDescription point_field_fields[] = {
    {"name", string}, {"offset", uint32}, {"datatype", uint8}, {"count", uint32}};
constexpr FieldDescription point_cloud2_fields[] = {
    {"header", nested, 0, 0, header_t}, {"height", uint32}, {"width", uint32},
    {"fields", sequence_of(nested), 0, 0, point_field_t}, {"is_bigendian", boolean},
    {"point_step", uint32}, {"row_step", uint32}, {"data", sequence_of(uint8)},
    {"is_dense", boolean}};
constexpr FieldDescription roi_fields[] = {{"x_offset", uint32}, {"y_offset", uint32},
                                           {"height", uint32}, {"width", uint32},
                                           {"do_rectify", boolean}};
constexpr FieldDescription camera_info_fields[] = {
    {"header", nested, 0, 0, header_t}, {"height", uint32}, {"width", uint32},
    {"distortion_model", string}, {"d", sequence_of(float64)}, {"k", array_of(float64), 9},
    {"r", array_of(float64), 9}, {"p", array_of(float64), 12}, {"binning_x", uint32},
    {"binning_y", uint32}, {"roi", nested, 0, 0, roi_t}};
constexpr FieldDescription vector3_fields[] = {{"x", float64}, {"y", float64}, {"z", float64}};
constexpr FieldDescription quaternion_fields[] = {
    {"x", float64}, {"y", float64}, {"z", float64}, {"w", float64}};
constexpr FieldDescription transform_fields[] = {{"translation", nested, 0, 0, vector3_t},
                                                 {"rotation", nested, 0, 0, quaternion_t}};
constexpr FieldDescription transform_stamped_fields[] = {
    {"header", nested, 0, 0, header_t}, {"child_frame_id", string},
    {"transform", nested, 0, 0, transform_t}};
constexpr FieldDescription tf_message_fields[] = {
    {"transforms", sequence_of(nested), 0, 0, transform_stamped_t}};
constexpr FieldDescription gid_fields[] = {{"data", array_of(uint8), 16}};  // char[16]
constexpr FieldDescription node_entities_fields[] = {
    {"node_namespace", bounded_string, 0, 256}, {"node_name", bounded_string, 0, 256},
    {"reader_gid_seq", sequence_of(nested), 0, 0, gid_t},
    {"writer_gid_seq", sequence_of(nested), 0, 0, gid_t}};
constexpr FieldDescription participant_entities_fields[] = {
    {"gid", nested, 0, 0, gid_t},
    {"node_entities_info_seq", sequence_of(nested), 0, 0, node_entities_t}};
// diagnostic_msgs: DiagnosticStatus's constants (OK … STALE) do not enter the hash.
constexpr FieldDescription key_value_fields[] = {{"key", string}, {"value", string}};
constexpr FieldDescription diagnostic_status_fields[] = {
    {"level", byte_}, {"name", string}, {"message", string}, {"hardware_id", string},
    {"values", sequence_of(nested), 0, 0, key_value_t}};
constexpr FieldDescription diagnostic_array_fields[] = {
    {"header", nested, 0, 0, header_t},
    {"status", sequence_of(nested), 0, 0, diagnostic_status_t}};

constexpr TypeDescription types[] = {
    {time_t_, time_fields},
    {header_t, header_fields},
    {"sensor_msgs/msg/Image", image_fields},
    {"sensor_msgs/msg/CompressedImage", compressed_image_fields},
    {point_field_t, point_field_fields},
    {"sensor_msgs/msg/PointCloud2", point_cloud2_fields},
    {roi_t, roi_fields},
    {"sensor_msgs/msg/CameraInfo", camera_info_fields},
    {vector3_t, vector3_fields},
    {quaternion_t, quaternion_fields},
    {transform_t, transform_fields},
    {transform_stamped_t, transform_stamped_fields},
    {"tf2_msgs/msg/TFMessage", tf_message_fields},
    {gid_t, gid_fields},
    {node_entities_t, node_entities_fields},
    {"rmw_dds_common/msg/ParticipantEntitiesInfo", participant_entities_fields},
    {key_value_t, key_value_fields},
    {diagnostic_status_t, diagnostic_status_fields},
    {"diagnostic_msgs/msg/DiagnosticArray", diagnostic_array_fields},
};

const TypeDescription* find_type(std::string_view name) {
  for (const TypeDescription& t : types) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

// Every type `type` references, directly or not (a std::set keeps them sorted by name, as rosidl
// sorts referenced_type_descriptions).
void collect_references(const TypeDescription& type, std::set<std::string_view>& out) {
  for (const FieldDescription& f : type.fields) {
    if (f.nested_type.empty() || !out.insert(f.nested_type).second) continue;
    if (const TypeDescription* nested_type = find_type(f.nested_type)) {
      collect_references(*nested_type, out);
    }
  }
}

// {"type_name": "…", "fields": [{"name": "…", "type": {"type_id": …, "capacity": …,
// "string_capacity": …, "nested_type_name": "…"}}, …]} exactly as Python's json.dumps writes it
// with separators (", ", ": "). Names are plain ASCII, so nothing needs escaping.
void append_type(std::string& json, const TypeDescription& type) {
  json += "{\"type_name\": \"";
  json += type.name;
  json += "\", \"fields\": [";
  for (std::size_t i = 0; i < type.fields.size(); ++i) {
    const FieldDescription& f = type.fields[i];
    if (i != 0) json += ", ";
    json += "{\"name\": \"";
    json += f.name;
    json += "\", \"type\": {\"type_id\": " + std::to_string(f.type_id) +
            ", \"capacity\": " + std::to_string(f.capacity) +
            ", \"string_capacity\": " + std::to_string(f.string_capacity) +
            ", \"nested_type_name\": \"";
    json += f.nested_type;
    json += "\"}}";
  }
  json += "]}";
}

std::string description_json(const TypeDescription& type) {
  std::set<std::string_view> references;
  collect_references(type, references);
  std::string json = "{\"type_description\": ";
  append_type(json, type);
  json += ", \"referenced_type_descriptions\": [";
  bool first = true;
  for (std::string_view name : references) {
    if (!first) json += ", ";
    first = false;
    append_type(json, *find_type(name));
  }
  json += "]}";
  return json;
}

std::string rihs01_of(const TypeDescription& type) {
  static constexpr char hex[] = "0123456789abcdef";
  std::string out = "RIHS01_";
  for (std::uint8_t b : sha256(description_json(type))) {
    out += hex[b >> 4];
    out += hex[b & 15];
  }
  return out;
}

const std::map<std::string_view, std::string>& all_hashes() {
  static const std::map<std::string_view, std::string> hashes = [] {
    std::map<std::string_view, std::string> m;
    for (const TypeDescription& t : types) m.emplace(t.name, rihs01_of(t));
    return m;
  }();
  return hashes;
}

}  // namespace

std::string_view rihs01_type_hash(std::string_view ros_type_name) noexcept {
  const auto& hashes = all_hashes();
  const auto it = hashes.find(ros_type_name);
  return it == hashes.end() ? std::string_view{} : std::string_view{it->second};
}

std::string_view rihs01_type_hash(MessageType type) noexcept {
  return rihs01_type_hash(ros_type_name(type));
}

std::string type_description_json(std::string_view ros_type_name) {
  const TypeDescription* type = find_type(ros_type_name);
  return type == nullptr ? std::string{} : description_json(*type);
}

}  // namespace sim::ros2
