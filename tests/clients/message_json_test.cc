// message_to_json (rdtf-echo, the bus fuzz target) against the schema check's idea of a message:
// every fingerprint type_of accepts has a decoder, and a nested struct's fingerprint is no message
// (the fuzz target requires a decoded message for every datagram that passes the check).
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <rdtf/blob_chunk_t.hpp>
#include <rdtf/blob_request_t.hpp>
#include <rdtf/blob_unavailable_t.hpp>
#include <rdtf/delta_t.hpp>
#include <rdtf/description_chunk_t.hpp>
#include <rdtf/file_t.hpp>
#include <rdtf/manifest_t.hpp>
#include <rdtf/description_t.hpp>
#include <rdtf/diagnostic_t.hpp>
#include <rdtf/inertia_table_t.hpp>
#include <rdtf/joint_command_t.hpp>
#include <rdtf/joint_state_t.hpp>
#include <rdtf/link_inertia_t.hpp>
#include <rdtf/link_state_t.hpp>
#include <rdtf/model_error_t.hpp>
#include <rdtf/model_removed_t.hpp>
#include <rdtf/model_saving_t.hpp>
#include <rdtf/request_t.hpp>
#include <rdtf/status_t.hpp>
#include <rdtf/validation_report_t.hpp>

#include "message_json.h"
#include "safe_decode.h"

namespace rdtf {
namespace {

// A value-initialised message (every count 0, every string empty), encoded with its fingerprint
// (lcm-gen's encode() writes one for a nested struct too, as an attacker would).
template <typename Message>
std::vector<std::uint8_t> encoded_empty() {
  const Message message{};
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

TEST(MessageJson, EveryTypeTheSchemaCheckAcceptsHasADecoderAndNestedStructsAreNoMessages) {
  const std::map<std::string, std::function<std::vector<std::uint8_t>()>, std::less<>> encoders = {
      {"blob_chunk_t", encoded_empty<rdtf::blob_chunk_t>},
      {"blob_request_t", encoded_empty<rdtf::blob_request_t>},
      {"blob_unavailable_t", encoded_empty<rdtf::blob_unavailable_t>},
      {"description_t", encoded_empty<rdtf::description_t>},
      {"description_chunk_t", encoded_empty<rdtf::description_chunk_t>},
      {"delta_t", encoded_empty<rdtf::delta_t>},
      {"delta_change_t", encoded_empty<rdtf::delta_change_t>},
      {"diagnostic_t", encoded_empty<rdtf::diagnostic_t>},
      {"file_t", encoded_empty<rdtf::file_t>},
      {"inertia_table_t", encoded_empty<rdtf::inertia_table_t>},
      {"joint_command_t", encoded_empty<rdtf::joint_command_t>},
      {"joint_state_t", encoded_empty<rdtf::joint_state_t>},
      {"link_inertia_t", encoded_empty<rdtf::link_inertia_t>},
      {"link_state_t", encoded_empty<rdtf::link_state_t>},
      {"manifest_t", encoded_empty<rdtf::manifest_t>},
      {"model_error_t", encoded_empty<rdtf::model_error_t>},
      {"model_removed_t", encoded_empty<rdtf::model_removed_t>},
      {"model_saving_t", encoded_empty<rdtf::model_saving_t>},
      {"request_t", encoded_empty<rdtf::request_t>},
      {"status_t", encoded_empty<rdtf::status_t>},
      {"validation_report_t", encoded_empty<rdtf::validation_report_t>}};
  const auto names = lcm_safe::lcm_type_names();
  ASSERT_EQ(names.size(), encoders.size()) << "a type in lcmtypes/ this test does not know";
  std::size_t messages = 0;
  for (const auto name : names) {
    const auto encoder = encoders.find(name);
    ASSERT_NE(encoder, encoders.end()) << name << " is in lcmtypes/ but not in this test";
    const auto bytes = encoder->second();
    const auto json = clients::message_to_json(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
    if (lcm_safe::is_message_type(name)) {
      ++messages;
      EXPECT_EQ(lcm_safe::type_of(bytes.data(), bytes.size()), name);
      EXPECT_EQ(lcm_safe::check_known(bytes.data(), bytes.size()), "") << name;
      EXPECT_TRUE(json.has_value()) << name << " passes the schema check but message_to_json has no decoder";
    } else {
      EXPECT_EQ(lcm_safe::type_of(bytes.data(), bytes.size()), "") << name;
      EXPECT_EQ(lcm_safe::check_known(bytes.data(), bytes.size()), "not an rdtf type") << name;
      EXPECT_FALSE(json.has_value()) << name;
    }
  }
  EXPECT_EQ(messages, 17u);
  // Empty arrays with constant inner dimensions (link_state_t's position[num_links][3]) pass.
  const auto links = encoded_empty<rdtf::link_state_t>();
  EXPECT_EQ(lcm_safe::check_known(links.data(), links.size()), "");
  EXPECT_FALSE(lcm_safe::is_message_type("diagnostic_t"));
  EXPECT_FALSE(lcm_safe::is_message_type("link_inertia_t"));
  EXPECT_FALSE(lcm_safe::is_message_type("file_t"));
  EXPECT_FALSE(lcm_safe::is_message_type("delta_change_t"));
  EXPECT_FALSE(lcm_safe::is_message_type("no_such_t"));
}

template <typename Message>
nlohmann::ordered_json json_of(const Message& message) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  const auto json = clients::message_to_json(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  if (!json) throw std::runtime_error(std::string(Message::getTypeName()) + " not decoded");
  return *json;
}

// Every per-joint and per-link message prints both names: the URDF's (name) and the glTF node's.
TEST(MessageJson, StatesAndInertiaPrintTheUrdfAndTheGltfNames) {
  rdtf::joint_state_t joints{};
  joints.num_joints = 1;
  joints.name = {"elbow_joint"};
  joints.gltf_name = {"elbow joint"};
  joints.position = {0.25};
  joints.velocity = {0.5};
  joints.effort = {-1};
  const auto j = json_of(joints);
  EXPECT_EQ(j["name"], nlohmann::ordered_json::array({"elbow_joint"}));
  EXPECT_EQ(j["gltf_name"], nlohmann::ordered_json::array({"elbow joint"}));
  EXPECT_EQ(j["position"], nlohmann::ordered_json::array({0.25}));

  rdtf::link_state_t links{};
  links.num_links = 2;
  links.name = {"upper_arm", "upper_arm_2"};
  links.gltf_name = {"upper arm", "upper_arm"};
  links.position = {{1, 2, 3}, {4, 5, 6}};
  links.orientation = {{1, 0, 0, 0}, {1, 0, 0, 0}};
  links.linear_velocity = {{0, 0, 0}, {0, 0, 0}};
  links.angular_velocity = {{0, 0, 0}, {0, 0, 0}};
  const auto l = json_of(links);
  EXPECT_EQ(l["name"], nlohmann::ordered_json::array({"upper_arm", "upper_arm_2"}));
  EXPECT_EQ(l["gltf_name"], nlohmann::ordered_json::array({"upper arm", "upper_arm"}));

  rdtf::inertia_table_t table{};
  rdtf::link_inertia_t row{};
  row.name = "upper_arm";
  row.gltf_name = "upper arm";
  row.node = 3;
  row.mass = 1.5;
  table.links = {row};
  table.num_links = 1;
  const auto t = json_of(table);
  ASSERT_EQ(t["links"].size(), 1u);
  EXPECT_EQ(t["links"][0]["name"], "upper_arm");
  EXPECT_EQ(t["links"][0]["gltf_name"], "upper arm");
  EXPECT_EQ(t["links"][0]["node"], 3);
}

}  // namespace
}  // namespace rdtf
