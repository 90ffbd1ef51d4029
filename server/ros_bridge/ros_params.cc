#include "ros_params.h"

#include <ros/param.h>

#include <sstream>
#include <utility>
#include <vector>

namespace objmap::ros_bridge {

std::string DescribeParam(const XmlRpc::XmlRpcValue& value) {
  XmlRpc::XmlRpcValue copy = value;  // the conversions are not const
  switch (copy.getType()) {
    case XmlRpc::XmlRpcValue::TypeArray:
      return "a list";
    case XmlRpc::XmlRpcValue::TypeStruct:
      return "a mapping";
    case XmlRpc::XmlRpcValue::TypeString:
      return "'" + static_cast<std::string>(copy) + "'";
    case XmlRpc::XmlRpcValue::TypeBoolean:
      return static_cast<bool>(copy) ? "true" : "false";
    case XmlRpc::XmlRpcValue::TypeInt:
      return std::to_string(static_cast<int>(copy));
    case XmlRpc::XmlRpcValue::TypeDouble: {
      std::ostringstream text;
      text << static_cast<double>(copy);
      return text.str();
    }
    default:
      return "'" + copy.toXml() + "'";  // dates and binary data, as XML-RPC writes them
  }
}

RosParamReader::RosParamReader(const ros::NodeHandle& private_node, std::string parameter_list_hint)
    : node_(private_node), parameter_list_hint_(std::move(parameter_list_hint)) {}

bool RosParamReader::Fetch(const char* key, XmlRpc::XmlRpcValue* raw) {
  const std::string name = section_ + key;
  known_.insert(node_.resolveName(name));
  return ok() && node_.getParam(name, *raw);
}

void RosParamReader::Fail(const std::string& key, const std::string& problem) {
  error_ = "~" + section_ + key + ": " + problem;
}

void RosParamReader::Finish() {
  if (!ok()) return;
  std::vector<std::string> names;
  if (!ros::param::getParamNames(names)) {
    error_ = "the parameter server's names could not be listed";
    return;
  }
  const std::string prefix = node_.getNamespace() + "/";
  for (const std::string& name : names) {
    if (name.rfind(prefix, 0) != 0 || known_.count(name) != 0) continue;
    error_ =
        "~" + name.substr(prefix.size()) + ": unknown parameter (" + parameter_list_hint_ + ")";
    return;
  }
}

}  // namespace objmap::ros_bridge
