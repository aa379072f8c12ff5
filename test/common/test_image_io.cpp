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
  expectReadError(dir + "/huge.pgm", "more than the limit");
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
  EXPECT_THROW(writeImage(dir + "/good.png/a.png", randomImage(CV_8UC1)), InputError);  // a file as folder
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
  // Missing parent folders are created (export_octomap --out new/folder/map.bt).
  writeTextAtomically(dir + "/new/folder/x.txt", "x", "test file");
  EXPECT_EQ(readTextFile(dir + "/new/folder/x.txt", "test file"), "x");
  EXPECT_THROW(writeTextAtomically(dir + "/out.txt/x.txt", "x", "test file"), InputError);  // a file as parent
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

// The output folder of a run: every file or none, the previous run's set kept on failure, one run at a time, and
// never an input replaced.
TEST(OutputFolder, WritesTheWholeSetOrNothing) {
  const std::string dir = testing::makeTempDir("output_folder");
  const std::string out = dir + "/out";
  {
    OutputFolder folder(out, {});
    writeTextAtomically(folder.file("a.txt"), "first a", "test file");
    writeTextAtomically(folder.file("b.txt"), "first b", "test file");
    EXPECT_FALSE(std::filesystem::exists(out + "/a.txt")) << "nothing is in place before commit()";
    folder.commit();
  }
  const std::vector<std::string> first_set{"a.txt", "b.txt"};
  EXPECT_EQ(testing::fileNames(out), first_set) << "the staging folder is gone";
  {
    // A run that fails after writing one file changes nothing.
    OutputFolder folder(out, {});
    writeTextAtomically(folder.file("a.txt"), "second a", "test file");
  }
  {
    OutputFolder folder(dir + "/never", {});  // a folder it created, left empty: removed
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/never"));
  EXPECT_EQ(readTextFile(out + "/a.txt", "test file"), "first a");
  EXPECT_EQ(testing::fileNames(out), first_set);
  {
    // A blocked name (a folder where a file goes) is found before anything moves.
    OutputFolder folder(out, {});
    writeTextAtomically(folder.file("a.txt"), "third a", "test file");
    writeTextAtomically(folder.file("c.txt"), "third c", "test file");
    std::filesystem::create_directory(out + "/c.txt");
    EXPECT_NE(testing::inputErrorMessage([&] { folder.commit(); }).find("c.txt: is a folder"), std::string::npos);
    EXPECT_EQ(readTextFile(out + "/a.txt", "test file"), "first a");
  }
}

TEST(OutputFolder, OneRunAtATimeAndNoInputReplaced) {
  const std::string dir = testing::makeTempDir("output_folder_lock");
  const std::string out = dir + "/out";
  std::filesystem::create_directories(out);
  {
    OutputFolder first(out, {});
    EXPECT_NE(testing::inputErrorMessage([&] { OutputFolder second(out, {}); }).find("another run is writing"),
              std::string::npos);
  }
  std::ofstream(out + "/map.yaml") << "image: map.pgm\n";
  OutputFolder folder(dir + "/./out/", {out + "/map.yaml", ""});  // the lock went with the first run
  EXPECT_NO_THROW(folder.file("rooms.png"));
  EXPECT_NE(testing::inputErrorMessage([&] { folder.file("map.yaml"); }).find("would replace the input"),
            std::string::npos);
  EXPECT_EQ(readTextFile(out + "/map.yaml", "test file"), "image: map.pgm\n");
}

TEST(OutputFolder, RemovesTheStagingFoldersOfKilledRuns) {
  const std::string dir = testing::makeTempDir("output_folder_stale");
  const pid_t child = fork();
  if (child == 0) _exit(0);
  ASSERT_GT(child, 0);
  ASSERT_EQ(waitpid(child, nullptr, 0), child);
  std::filesystem::create_directories(dir + "/.partial" + std::to_string(child));
  std::ofstream(dir + "/.partial" + std::to_string(child) + "/rooms.png") << "half";
  OutputFolder folder(dir, {});
  EXPECT_FALSE(std::filesystem::exists(dir + "/.partial" + std::to_string(child)));
}

TEST(ImageIo, AnImageDeclaringTooManyPixelsIsRefusedBeforeItsPixelsAreAllocated) {
  const std::string dir = testing::makeTempDir("image_limit");
  // A PNG of 45 bytes whose header declares 100000 x 100000 grey pixels (1e10 bytes): signature, IHDR, an empty
  // IDAT (the header ends at the first IDAT).
  const unsigned char png[] = {0x89, 'P',  'N',  'G',  0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 'I',  'H',  'D',
                               'R',  0x00, 0x01, 0x86, 0xa0, 0x00, 0x01, 0x86, 0xa0, 0x08, 0x00, 0x00, 0x00, 0x00, 0x8d,
                               0x39, 0x54, 0x14, 0x00, 0x00, 0x00, 0x00, 'I',  'D',  'A',  'T',  0x35, 0xaf, 0x06, 0x1e};
  std::ofstream(dir + "/huge.png", std::ios::binary).write(reinterpret_cast<const char*>(png), sizeof(png));
  std::ofstream(dir + "/huge.pgm") << "P5\n60000 60000\n255\n";
  for (const char* name : {"/huge.png", "/huge.pgm"}) {
    const std::string message = testing::inputErrorMessage([&] { readImage(dir + name); });
    EXPECT_NE(message.find("more than the limit of 25000000 pixels"), std::string::npos) << message;
  }
  EXPECT_NE(testing::inputErrorMessage([&] { readImage(dir); }).find("is a folder, not an image file"),
            std::string::npos);
}

TEST(ImageIo, APlainPgmLongerThanItsPixelsCanFillIsRefusedBeforeItIsRead) {
  const std::string dir = testing::makeTempDir("image_padding");
  {
    std::ofstream padded(dir + "/padded.pgm");
    padded << "P2\n2 2\n255\n0 255 255 0";
    padded << std::string(200000, ' ') << "\n";  // a 2 x 2 image of 200 kB (the issue's was gigabytes)
    std::ofstream(dir + "/long_header.pgm") << "P2\n#" << std::string(70000, 'c') << "\n2 2\n255\n0 255 255 0\n";
  }
  const std::string padded = testing::inputErrorMessage([&] { readImage(dir + "/padded.pgm"); });
  EXPECT_NE(padded.find("the file's size in bytes is 200"), std::string::npos) << padded;
  EXPECT_NE(padded.find("what the pixels its header declares can fill"), std::string::npos) << padded;
  EXPECT_FALSE(testing::inputErrorMessage([&] { readImage(dir + "/long_header.pgm"); }).empty());
  std::ofstream(dir + "/fine.pgm") << "P2\n2 2\n255\n0 255 255 0\n\n";
  EXPECT_EQ(readImage(dir + "/fine.pgm").total(), 4u);
}

}  // namespace
}  // namespace hidden_rooms::common
