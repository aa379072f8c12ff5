#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <opencv2/imgcodecs.hpp>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/input_error.h"
#include "test_util.h"

// OpenCV's imgcodecs (not linked into the package's libraries) is the independent reference here.
namespace hidden_rooms::common {
namespace {

bool sameImage(const cv::Mat& a, const cv::Mat& b) {
  return a.type() == b.type() && a.size() == b.size() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

cv::Mat randomImage(int type) {
  cv::Mat image(13, 17, type);
  cv::RNG rng(7);
  rng.fill(image, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(type) == CV_16U ? 65536 : 256);
  return image;
}

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

void expectReadError(const std::string& path, const std::string& fragment) {
  try {
    readImage(path);
    FAIL() << "no error for " << path;
  } catch (const InputError& error) {
    EXPECT_EQ(error.source(), path);
    EXPECT_NE(std::string(error.what()).find(fragment), std::string::npos) << error.what();
  }
}

TEST(ImageIo, PngRoundTripsEveryPixelTypeLikeOpenCv) {
  const std::string dir = testing::makeTempDir("image_io_png");
  for (int type : {CV_8UC1, CV_16UC1, CV_8UC2, CV_8UC3, CV_8UC4, CV_16UC3}) {
    SCOPED_TRACE(cv::typeToString(type));
    const cv::Mat image = randomImage(type);
    const std::string ours = dir + "/ours.png";
    writeImage(ours, image);
    EXPECT_TRUE(sameImage(readImage(ours), image));
    if (type != CV_8UC2) {  // OpenCV reads grey + alpha as BGRA
      EXPECT_TRUE(sameImage(cv::imread(ours, cv::IMREAD_UNCHANGED), image));
      const std::string theirs = dir + "/theirs.png";
      ASSERT_TRUE(cv::imwrite(theirs, image));
      EXPECT_TRUE(sameImage(readImage(theirs), image));
    }
  }
}

TEST(ImageIo, PgmAndPpmBinaryAndTextMatchOpenCv) {
  const std::string dir = testing::makeTempDir("image_io_pnm");
  for (int type : {CV_8UC1, CV_16UC1}) {
    const cv::Mat image = randomImage(type);
    writeImage(dir + "/ours.pgm", image);
    EXPECT_TRUE(sameImage(readImage(dir + "/ours.pgm"), image));
    EXPECT_TRUE(sameImage(cv::imread(dir + "/ours.pgm", cv::IMREAD_UNCHANGED), image));
  }
  const cv::Mat colour = randomImage(CV_8UC3);
  ASSERT_TRUE(cv::imwrite(dir + "/colour.ppm", colour));
  EXPECT_TRUE(sameImage(readImage(dir + "/colour.ppm"), colour));
  // Plain (ASCII) formats with comments; values above maxval are clipped.
  writeBytes(dir + "/plain.pgm", "P2\n# a comment\n3 2\n# another\n255\n0 128 255\n7 8 300\n");
  cv::Mat1b expected(2, 3);
  expected << 0, 128, 255, 7, 8, 255;
  EXPECT_TRUE(sameImage(readImage(dir + "/plain.pgm"), expected));
  writeBytes(dir + "/plain.ppm", "P3 1 1 255\n10 20 30\n");
  EXPECT_EQ(readImage(dir + "/plain.ppm").at<cv::Vec3b>(0, 0), cv::Vec3b(30, 20, 10));
}

TEST(ImageIo, BadFilesGiveErrorsNamingTheFile) {
  const std::string dir = testing::makeTempDir("image_io_bad");
  expectReadError(dir + "/missing.png", "does not exist");
  writeBytes(dir + "/text.png", "just some text");
  expectReadError(dir + "/text.png", "not a PNG, PGM or PPM");
  writeBytes(dir + "/empty.pgm", "");
  expectReadError(dir + "/empty.pgm", "not a PNG, PGM or PPM");
  writeImage(dir + "/good.png", randomImage(CV_8UC1));
  std::ifstream good(dir + "/good.png", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(good)), std::istreambuf_iterator<char>());
  writeBytes(dir + "/cut.png", bytes.substr(0, bytes.size() / 2));
  expectReadError(dir + "/cut.png", "cannot read PNG");
  writeBytes(dir + "/cut.pgm", "P5\n4 4\n255\nabc");
  expectReadError(dir + "/cut.pgm", "truncated");
  writeBytes(dir + "/huge.pgm", "P5\n65536 65536\n255\n");
  expectReadError(dir + "/huge.pgm", "truncated");
  writeBytes(dir + "/letters.pgm", "P2\nthree 2\n255\n");
  expectReadError(dir + "/letters.pgm", "not a number");
  writeBytes(dir + "/zero.pgm", "P5\n0 2\n255\n");
  expectReadError(dir + "/zero.pgm", "out of range");
  writeBytes(dir + "/short.pgm", "P2\n2 2\n255\n1 2 3\n");
  expectReadError(dir + "/short.pgm", "truncated");

  EXPECT_THROW(writeImage(dir + "/picture.jpg", randomImage(CV_8UC1)), InputError);
  EXPECT_THROW(writeImage(dir + "/colour.pgm", randomImage(CV_8UC3)), InputError);
  EXPECT_THROW(writeImage(dir + "/float.png", cv::Mat1f(2, 2, 0.5f)), InputError);
  EXPECT_THROW(writeImage(dir + "/empty.png", cv::Mat()), InputError);
  EXPECT_THROW(writeImage(dir + "/no_such_dir/a.png", randomImage(CV_8UC1)), InputError);
}

TEST(ImageIo, ReadsTheBenchmarkImagesLikeOpenCv) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  const std::string root = testing::sharedDir() + "/data/closed_door_benchmark";
  for (const char* case_dir : {"office1_fs/08_doors", "Sabadell1/12_doors"})
    for (const char* name : {"map.png", "gt_rooms.png"}) {
      const std::string path = root + "/" + case_dir + "/" + name;
      EXPECT_TRUE(sameImage(readImage(path), cv::imread(path, cv::IMREAD_UNCHANGED))) << path;
    }
}

}  // namespace
}  // namespace hidden_rooms::common

namespace hidden_rooms::common {
namespace {

TEST(FileIo, WritesAtomicallyAndLeavesNoPartialFile) {
  const std::string dir = testing::makeTempDir("write_atomically");
  const std::string path = dir + "/out.txt";
  writeTextAtomically(path, "first\n", "test file");
  EXPECT_EQ(readTextFile(path, "test file"), "first\n");
  // A writer that fails half-way leaves the old file as it was and nothing else in the folder.
  EXPECT_THROW(writeAtomically(path,
                               [](const std::string& temporary) {
                                 std::ofstream(temporary) << "half";
                                 throw InputError("test", "failed half-way");
                               }),
               InputError);
  EXPECT_EQ(readTextFile(path, "test file"), "first\n");
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), std::filesystem::directory_iterator()), 1);
  // An image write that fails (unsupported pixel type) leaves nothing either.
  EXPECT_THROW(writeImage(dir + "/bad.png", cv::Mat(2, 2, CV_32FC1, cv::Scalar(0))), InputError);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), std::filesystem::directory_iterator()), 1);
  EXPECT_THROW(writeTextAtomically(dir + "/no/such/folder/x.txt", "x", "test file"), InputError);
}

TEST(FileIo, RemovesTheTemporariesOfKilledWriters) {
  const std::string dir = testing::makeTempDir("stale_temporaries");
  const std::string path = dir + "/map.pgm";
  // A writer that is gone (a child that exited, reaped) and one that still runs (this test's parent).
  const pid_t child = fork();
  if (child == 0) _exit(0);
  ASSERT_GT(child, 0);
  ASSERT_EQ(waitpid(child, nullptr, 0), child);
  const std::string dead = path + ".partial" + std::to_string(child);
  const std::string alive = path + ".partial" + std::to_string(getppid());
  const std::string other = dir + "/map.yaml.partial" + std::to_string(child);  // another target's
  for (const std::string& file : {dead, alive, other}) std::ofstream(file) << "half";
  writeTextAtomically(path, "P5\n", "test file");
  EXPECT_EQ(readTextFile(path, "test file"), "P5\n");
  EXPECT_FALSE(std::filesystem::exists(dead));
  EXPECT_TRUE(std::filesystem::exists(alive));
  EXPECT_TRUE(std::filesystem::exists(other));
}

}  // namespace
}  // namespace hidden_rooms::common
