#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "hidden_rooms/prediction/room_network.h"

namespace hidden_rooms::prediction {
namespace {

// Channel c of a door's window (kWindowCells square).
cv::Mat1f channel(const cv::Mat& input, int c) {
  return cv::Mat1f(kWindowCells, kWindowCells, const_cast<float*>(input.ptr<float>(c))).clone();
}

// States (0 unknown, 1 free, 2 occupied) of a 10 m x 6 m map at 5 cm: a free corridor 1 m high along the bottom,
// its upper wall at row 99, the rest unknown.
cv::Mat1b corridorStates() {
  cv::Mat1b states(120, 200, static_cast<uint8_t>(0));
  states(cv::Rect(0, 100, 200, 20)).setTo(1);
  states(cv::Rect(0, 99, 200, 1)).setTo(2);
  return states;
}

TEST(RoomNetwork, WindowIsCentredOnTheDoorAndUnknownOutsideTheMap) {
  const cv::Mat1b states = corridorStates();
  const std::vector<NetworkDoor> doors{{cv::Point(100, 99), 1.0}, {cv::Point(160, 99), 1.0}};
  EXPECT_EQ(windowPixels(0.05), 384);  // 96 cells of 0.2 m
  const cv::Mat input = doorWindowInput(states, 0.05, doors, 0);
  ASSERT_EQ(input.dims, 3);
  EXPECT_EQ(input.size[0], kWindowChannels);
  // Each cell's occupied, free and unknown shares sum to one.
  const cv::Mat1f shares = channel(input, 0) + channel(input, 1) + channel(input, 2);
  double low, high;
  cv::minMaxLoc(shares, &low, &high);
  EXPECT_NEAR(low, 1.0, 1e-5);
  EXPECT_NEAR(high, 1.0, 1e-5);
  // The door lies at the window's centre: the corridor's free cells just below it (map rows 100 to 119: window
  // rows 48 to 52), and the map's edge 2.4 m below the door: unknown beyond.
  EXPECT_FLOAT_EQ(channel(input, 1)(50, 48), 1.0f);
  EXPECT_FLOAT_EQ(channel(input, 2)(60, 48), 1.0f);
  EXPECT_FLOAT_EQ(channel(input, 2)(40, 48), 1.0f);
  // Its disc (radius 0.5 m) in channel 3, the other door's, 3 m to the right, in channel 4.
  EXPECT_GT(channel(input, 3)(48, 48), 0.9f);
  EXPECT_FLOAT_EQ(channel(input, 3)(48, 63), 0.0f);
  EXPECT_GT(channel(input, 4)(48, 63), 0.9f);
  EXPECT_FLOAT_EQ(channel(input, 4)(48, 48), 0.0f);
}

TEST(RoomNetwork, ScoresEveryDoorOnItsWindow) {
  const cv::Mat1b states = corridorStates();
  const std::vector<NetworkDoor> doors{{cv::Point(100, 99), 1.0}, {cv::Point(160, 99), 1.0}};
  const std::vector<RoomScores> scores = roomScores(states, 0.05, doors);
  ASSERT_EQ(scores.size(), 2u);
  for (size_t i = 0; i < doors.size(); ++i) {
    EXPECT_EQ(scores[i].window, cv::Rect(doors[i].pixel.x - 192, doors[i].pixel.y - 192, 384, 384));
    EXPECT_EQ(scores[i].logits.size(), cv::Size(kWindowCells, kWindowCells));
    EXPECT_TRUE(cv::checkRange(scores[i].logits));
  }
  // The second door lies in the first one's window (the other doors' channel): alone, the first door scores
  // otherwise.
  const std::vector<RoomScores> alone = roomScores(states, 0.05, {doors[0]});
  EXPECT_GT(cv::norm(alone[0].logits, scores[0].logits, cv::NORM_INF), 0.0);
  EXPECT_TRUE(roomScores(states, 0.05, {}).empty());
}

// A door's room takes the cells whose score is above the threshold, connected to the door: hand-made scores of
// +2 just behind the door, -0.2 (probability 0.45) farther back, -3 elsewhere.
TEST(RoomNetwork, RoomIsTheConnectedScoresAboveTheThreshold) {
  const cv::Mat1b states = corridorStates();
  const std::vector<NetworkDoor> doors{{cv::Point(100, 99), 1.0}};
  RoomScores scores{cv::Rect(100 - 192, 99 - 192, 384, 384), cv::Mat1f(kWindowCells, kWindowCells, -3.0f)};
  scores.logits(cv::Rect(44, 43, 9, 5)).setTo(2.0f);   // map rows about 79 to 98
  scores.logits(cv::Rect(44, 38, 9, 5)).setTo(-0.2f);  // map rows about 59 to 78
  const auto in_room = [&](double min_probability, int row) {
    const std::vector<NetworkRoom> rooms = networkRooms(states, doors, {scores}, 0.05, 3, min_probability);
    EXPECT_EQ(rooms[0].box, cv::Rect(0, 0, 200, 120));
    return rooms[0].mask(row, 100) > 0;
  };
  EXPECT_TRUE(in_room(0.5, 90));
  EXPECT_FALSE(in_room(0.5, 70));
  EXPECT_TRUE(in_room(0.41, 90));
  EXPECT_TRUE(in_room(0.41, 70));
  EXPECT_FALSE(in_room(0.41, 40));
  EXPECT_FALSE(in_room(0.41, 105));  // the corridor is known: never a room
}

}  // namespace
}  // namespace hidden_rooms::prediction
