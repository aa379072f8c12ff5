#include "hidden_rooms/ros/parameters.h"

#include <XmlRpcValue.h>

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms {
namespace {

common::InputError wrongType(const std::string& name, const char* expected) {
  return common::InputError("~" + name, std::string("must be ") + expected);
}

}  // namespace

void readParameter(const ros::NodeHandle& nh, const std::string& name, double* value) {
  XmlRpc::XmlRpcValue parameter;
  if (!nh.getParam(name, parameter)) return;
  if (parameter.getType() == XmlRpc::XmlRpcValue::TypeDouble) *value = static_cast<double>(parameter);
  else if (parameter.getType() == XmlRpc::XmlRpcValue::TypeInt) *value = static_cast<int>(parameter);
  else throw wrongType(name, "a number");
}

void readParameter(const ros::NodeHandle& nh, const std::string& name, int* value) {
  XmlRpc::XmlRpcValue parameter;
  if (!nh.getParam(name, parameter)) return;
  if (parameter.getType() != XmlRpc::XmlRpcValue::TypeInt) throw wrongType(name, "an integer");
  *value = static_cast<int>(parameter);
}

void readParameter(const ros::NodeHandle& nh, const std::string& name, bool* value) {
  XmlRpc::XmlRpcValue parameter;
  if (!nh.getParam(name, parameter)) return;
  if (parameter.getType() != XmlRpc::XmlRpcValue::TypeBoolean) throw wrongType(name, "true or false");
  *value = static_cast<bool>(parameter);
}

void readParameter(const ros::NodeHandle& nh, const std::string& name, std::string* value) {
  XmlRpc::XmlRpcValue parameter;
  if (!nh.getParam(name, parameter)) return;
  if (parameter.getType() != XmlRpc::XmlRpcValue::TypeString) throw wrongType(name, "a string");
  *value = static_cast<std::string>(parameter);
}

void readTextParameter(const ros::NodeHandle& nh, const std::string& name, std::string* value) {
  XmlRpc::XmlRpcValue parameter;
  if (!nh.getParam(name, parameter)) return;
  if (parameter.getType() == XmlRpc::XmlRpcValue::TypeString) *value = static_cast<std::string>(parameter);
  else if (parameter.getType() == XmlRpc::XmlRpcValue::TypeInt) *value = std::to_string(static_cast<int>(parameter));
  else throw wrongType(name, "text or an integer");
}

void readPositiveParameter(const ros::NodeHandle& nh, const std::string& name, std::optional<double>* value) {
  double number = 0.0;
  readParameter(nh, name, &number);
  if (number > 0.0) *value = number;
}

}  // namespace hidden_rooms
