#pragma once
// Typed reading of a node's private ROS parameters into config structs, shared by objmap_node
// and objmap_dataset_player, so that both report mistyped and unknown parameters alike.

#include <ros/node_handle.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <set>
#include <string>
#include <type_traits>

namespace objmap::ros_bridge {

/// "'high'", "3", "true", "a list": a parameter value as an error message shows it.
[[nodiscard]] std::string DescribeParam(const XmlRpc::XmlRpcValue& value);

/// What a value of type T must look like, for messages ("expected a number, got 'high'").
template <typename T>
const char* ExpectedValue() {
  if constexpr (std::is_same_v<T, bool>) return "true or false";
  if constexpr (std::is_integral_v<T>) return "an integer";
  if constexpr (std::is_floating_point_v<T>) return "a number";
  return "a string";
}

/// Reads `~key` and `~section/key` parameters over config fields; a field keeps its default when
/// its parameter is not set. Every name read is remembered so that Finish() reports the
/// parameters left over: a misspelt key is an error, not a silent default. Stops at the first
/// problem. Used as the visitor of a config's key list (`v("rate", &config.rate_hz)`).
/// Thread-safety: one thread.
class RosParamReader {
 public:
  /// `parameter_list_hint` ends the unknown-parameter message, telling where the valid names
  /// are listed ("objmap_node's parameters are listed in launch/objmap.launch").
  RosParamReader(const ros::NodeHandle& private_node, std::string parameter_list_hint);

  void Section(const char* name) { section_ = std::string(name) + "/"; }
  void TopLevel() { section_.clear(); }

  /// bool, integers (integer parameters only), floating point (integer or double parameters)
  /// and strings.
  template <typename T>
  void operator()(const char* key, T* value) {
    XmlRpc::XmlRpcValue raw;
    if (!Fetch(key, &raw)) return;
    if (!Convert(raw, value)) {
      Fail(key, std::string("expected ") + ExpectedValue<T>() + ", got " + DescribeParam(raw));
    }
  }

  /// After the last key: every parameter in the private namespace must have been read.
  void Finish();

  [[nodiscard]] bool ok() const { return error_.empty(); }
  [[nodiscard]] const std::string& error() const { return error_; }

 protected:
  /// Remembers `key` (in the current section) as known and fetches its value; false when the
  /// parameter is not set or an earlier key failed.
  bool Fetch(const char* key, XmlRpc::XmlRpcValue* raw);
  /// Records "~section/key: <problem>" as the error (`key` may carry an index: "classes[2]").
  void Fail(const std::string& key, const std::string& problem);

 private:
  template <typename T>
  static bool Convert(XmlRpc::XmlRpcValue& value, T* out) {
    const auto type = value.getType();
    if constexpr (std::is_same_v<T, bool>) {
      if (type != XmlRpc::XmlRpcValue::TypeBoolean) return false;
      *out = static_cast<bool>(value);
    } else if constexpr (std::is_integral_v<T>) {
      if (type != XmlRpc::XmlRpcValue::TypeInt) return false;
      *out = static_cast<T>(static_cast<int>(value));
    } else if constexpr (std::is_floating_point_v<T>) {
      if (type == XmlRpc::XmlRpcValue::TypeInt) {
        *out = static_cast<T>(static_cast<int>(value));
      } else if (type == XmlRpc::XmlRpcValue::TypeDouble) {
        *out = static_cast<T>(static_cast<double>(value));
      } else {
        return false;
      }
    } else {
      if (type != XmlRpc::XmlRpcValue::TypeString) return false;
      *out = static_cast<std::string>(value);
    }
    return true;
  }

  const ros::NodeHandle& node_;
  std::string parameter_list_hint_;
  std::string section_;
  std::set<std::string> known_;
  std::string error_;
};

}  // namespace objmap::ros_bridge
