#include "occupancy_fusion/ros/ros_parameter_source.h"

#include <stdexcept>

#include <xmlrpcpp/XmlRpcValue.h>

namespace occupancy_fusion {
namespace {

using XmlRpc::XmlRpcValue;

[[noreturn]] void throwWrongType(const ros::NodeHandle& node_handle, const std::string& key,
                                 const char* expected) {
  throw std::invalid_argument("parameter '" + node_handle.resolveName(key) + "' must be " +
                              expected);
}

bool isNumber(const XmlRpcValue& value) {
  return value.getType() == XmlRpcValue::TypeDouble || value.getType() == XmlRpcValue::TypeInt;
}

double toDouble(XmlRpcValue& value) {
  return value.getType() == XmlRpcValue::TypeInt ? static_cast<double>(static_cast<int>(value))
                                                 : static_cast<double>(value);
}

// The raw value, or false when the key is absent.
bool lookUp(const ros::NodeHandle& node_handle, const std::string& key, XmlRpcValue* raw) {
  return node_handle.getParam(key, *raw);
}

}  // namespace

RosParameterSource::RosParameterSource(const ros::NodeHandle& node_handle)
    : node_handle_(node_handle) {}

bool RosParameterSource::get(const std::string& key, double* value) const {
  XmlRpcValue raw;
  if (!lookUp(node_handle_, key, &raw)) return false;
  if (!isNumber(raw)) throwWrongType(node_handle_, key, "a number");
  *value = toDouble(raw);
  return true;
}

bool RosParameterSource::get(const std::string& key, int* value) const {
  XmlRpcValue raw;
  if (!lookUp(node_handle_, key, &raw)) return false;
  if (raw.getType() != XmlRpcValue::TypeInt) throwWrongType(node_handle_, key, "an integer");
  *value = static_cast<int>(raw);
  return true;
}

bool RosParameterSource::get(const std::string& key, bool* value) const {
  XmlRpcValue raw;
  if (!lookUp(node_handle_, key, &raw)) return false;
  if (raw.getType() != XmlRpcValue::TypeBoolean) throwWrongType(node_handle_, key, "true or false");
  *value = static_cast<bool>(raw);
  return true;
}

bool RosParameterSource::get(const std::string& key, std::string* value) const {
  XmlRpcValue raw;
  if (!lookUp(node_handle_, key, &raw)) return false;
  if (raw.getType() != XmlRpcValue::TypeString) throwWrongType(node_handle_, key, "a string");
  *value = static_cast<std::string>(raw);
  return true;
}

bool RosParameterSource::get(const std::string& key, std::vector<std::string>* value) const {
  XmlRpcValue raw;
  if (!lookUp(node_handle_, key, &raw)) return false;
  if (raw.getType() != XmlRpcValue::TypeArray)
    throwWrongType(node_handle_, key, "a list of strings");
  std::vector<std::string> result;
  for (int i = 0; i < raw.size(); ++i) {
    if (raw[i].getType() != XmlRpcValue::TypeString) {
      throwWrongType(node_handle_, key, "a list of strings");
    }
    result.push_back(static_cast<std::string>(raw[i]));
  }
  *value = std::move(result);
  return true;
}

bool RosParameterSource::get(const std::string& key, std::vector<double>* value) const {
  XmlRpcValue raw;
  if (!lookUp(node_handle_, key, &raw)) return false;
  if (raw.getType() != XmlRpcValue::TypeArray)
    throwWrongType(node_handle_, key, "a list of numbers");
  std::vector<double> result;
  for (int i = 0; i < raw.size(); ++i) {
    if (!isNumber(raw[i])) throwWrongType(node_handle_, key, "a list of numbers");
    result.push_back(toDouble(raw[i]));
  }
  *value = std::move(result);
  return true;
}

std::vector<std::string> RosParameterSource::keys() const {
  std::vector<std::string> all;
  std::vector<std::string> relative;
  if (!node_handle_.getParamNames(all)) return relative;
  std::string prefix = node_handle_.getNamespace();
  if (prefix.empty() || prefix.back() != '/') prefix += '/';
  for (const std::string& name : all) {
    if (name.compare(0, prefix.size(), prefix) == 0) relative.push_back(name.substr(prefix.size()));
  }
  return relative;
}

}  // namespace occupancy_fusion
