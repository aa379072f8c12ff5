// use_hidden_rooms_messages: fills a PredictRooms request (a ClosedDoor, a PredictionParameter), serializes it as
// ROS does and reads it back; prints "round trip ok" and exits 0 when the copy equals the original.
#include <cstdio>
#include <vector>

#include <hidden_rooms/PredictRooms.h>
#include <ros/serialization.h>

int main() {
  hidden_rooms::PredictRooms::Request request;
  hidden_rooms::ClosedDoor door;
  door.id = 7;
  door.position.x = 1.5;
  door.width = 0.9;
  door.orientation = hidden_rooms::ClosedDoor::ALONG_Y;
  request.doors.push_back(door);
  hidden_rooms::PredictionParameter parameter;
  parameter.name = "default_min_depth";
  parameter.value = 1.5;
  request.parameters.push_back(parameter);
  request.method = "default";

  std::vector<uint8_t> buffer(ros::serialization::serializationLength(request));
  ros::serialization::OStream out(buffer.data(), static_cast<uint32_t>(buffer.size()));
  ros::serialization::serialize(out, request);
  hidden_rooms::PredictRooms::Request copy;
  ros::serialization::IStream in(buffer.data(), static_cast<uint32_t>(buffer.size()));
  ros::serialization::deserialize(in, copy);
  const bool same = copy.doors.size() == 1 && copy.doors[0].id == 7 && copy.doors[0].position.x == 1.5 &&
                    copy.doors[0].orientation == hidden_rooms::ClosedDoor::ALONG_Y &&
                    copy.parameters.size() == 1 && copy.parameters[0].name == parameter.name &&
                    copy.parameters[0].value == 1.5 && copy.method == "default";
  std::printf(same ? "round trip ok\n" : "round trip changed the request\n");
  return same ? 0 : 1;
}
