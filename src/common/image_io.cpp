#include "hidden_rooms/common/image_io.h"

#include <png.h>

#include <algorithm>
#include <cctype>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/input_limits.h"

namespace hidden_rooms::common {

namespace {

constexpr unsigned char kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

// RAII for libpng's simplified API state.
struct PngImage {
  png_image image;
  PngImage() {
    std::memset(&image, 0, sizeof(image));
    image.version = PNG_IMAGE_VERSION;
  }
  ~PngImage() { png_image_free(&image); }
};

// Refuses an image whose header declares more pixels than kMaxMapCells, before its pixels are allocated.
void checkImageSize(const std::string& path, double width, double height) {
  checkLimit(path, "the image's size (" + formatNumber(width) + " x " + formatNumber(height) + " pixels)",
             width * height, kMaxMapCells, " pixels");
}

cv::Mat readPng(const std::string& path) {
  PngImage png;
  if (!png_image_begin_read_from_file(&png.image, path.c_str()))
    throw InputError(path, std::string("cannot read PNG: ") + png.image.message);
  png_uint_32 format = png.image.format & ~PNG_FORMAT_FLAG_COLORMAP;
  // Linear (16-bit) data with alpha would come premultiplied: take such images as 8-bit.
  if ((format & PNG_FORMAT_FLAG_LINEAR) && (format & PNG_FORMAT_FLAG_ALPHA)) format &= ~PNG_FORMAT_FLAG_LINEAR;
  if (format & PNG_FORMAT_FLAG_COLOR) format |= PNG_FORMAT_FLAG_BGR;
  png.image.format = format;
  if (png.image.width == 0 || png.image.height == 0) throw InputError(path, "image is empty");
  checkImageSize(path, png.image.width, png.image.height);
  const int channels = PNG_IMAGE_SAMPLE_CHANNELS(format);
  const bool sixteen = (format & PNG_FORMAT_FLAG_LINEAR) != 0;
  cv::Mat image(static_cast<int>(png.image.height), static_cast<int>(png.image.width),
                CV_MAKETYPE(sixteen ? CV_16U : CV_8U, channels));
  const png_int_32 row_stride = static_cast<png_int_32>(image.step[0] / PNG_IMAGE_SAMPLE_COMPONENT_SIZE(format));
  if (!png_image_finish_read(&png.image, nullptr, image.data, row_stride, nullptr))
    throw InputError(path, std::string("cannot read PNG: ") + png.image.message);
  return image;
}

// Netpbm header token: skips white space and # comments.
bool nextToken(const std::string& data, size_t* pos, std::string* token) {
  while (*pos < data.size()) {
    if (data[*pos] == '#') {
      while (*pos < data.size() && data[*pos] != '\n') ++*pos;
    } else if (std::isspace(static_cast<unsigned char>(data[*pos]))) {
      ++*pos;
    } else {
      break;
    }
  }
  const size_t start = *pos;
  while (*pos < data.size() && !std::isspace(static_cast<unsigned char>(data[*pos])) && data[*pos] != '#') ++*pos;
  *token = data.substr(start, *pos - start);
  return !token->empty();
}

int headerNumber(const std::string& data, size_t* pos, const std::string& path, const char* what, int max_value) {
  std::string token;
  if (!nextToken(data, pos, &token)) throw InputError(path, std::string("Netpbm header ends before the ") + what);
  if (token.size() > 9 || !std::all_of(token.begin(), token.end(), [](char c) { return std::isdigit(c); }))
    throw InputError(path, std::string("Netpbm ") + what + " '" + token + "' is not a number");
  const int value = std::stoi(token);
  if (value <= 0 || value > max_value)
    throw InputError(path, std::string("Netpbm ") + what + " " + token + " is out of range");
  return value;
}

constexpr size_t kNetpbmHeaderBytes = 65536;      // a longer header (comments) is refused
constexpr size_t kMaxAsciiBytesPerSample = 16;    // digits and white space of one plain-PGM/PPM sample

struct NetpbmHeader {
  int width, height, max_value, channels;
  bool ascii;
  size_t pixels_start;  // offset of the first pixel byte (binary) or token (plain)
};

NetpbmHeader readNetpbmHeader(const std::string& path, const std::string& data) {
  NetpbmHeader header;
  const char kind = data[1];
  header.ascii = kind == '2' || kind == '3';
  header.channels = (kind == '3' || kind == '6') ? 3 : 1;
  size_t pos = 2;
  header.width = headerNumber(data, &pos, path, "width", 1 << 16);
  header.height = headerNumber(data, &pos, path, "height", 1 << 16);
  header.max_value = headerNumber(data, &pos, path, "maxval", 65535);
  checkImageSize(path, header.width, header.height);
  header.pixels_start = pos;
  return header;
}

// Refuses a file longer than its header's pixels can fill (a plain file padded with gigabytes of white space).
void checkNetpbmFileSize(const std::string& path, const std::string& head_bytes, size_t file_bytes) {
  const NetpbmHeader header = readNetpbmHeader(path, head_bytes);
  if (head_bytes.size() == kNetpbmHeaderBytes && header.pixels_start >= kNetpbmHeaderBytes)
    throw InputError(path, "Netpbm header is longer than " + std::to_string(kNetpbmHeaderBytes) + " bytes");
  const double samples = static_cast<double>(header.width) * header.height * header.channels;
  const double bytes_per_sample = header.ascii ? kMaxAsciiBytesPerSample : (header.max_value > 255 ? 2 : 1);
  checkLimit(path, "the file's size in bytes", static_cast<double>(file_bytes),
             static_cast<double>(header.pixels_start + kNetpbmHeaderBytes) + samples * bytes_per_sample,
             " (what the pixels its header declares can fill)");
}

cv::Mat readNetpbm(const std::string& path, const std::string& data) {
  const NetpbmHeader header = readNetpbmHeader(path, data);
  const int width = header.width, height = header.height, max_value = header.max_value, channels = header.channels;
  const bool ascii = header.ascii;
  size_t pos = header.pixels_start;
  const bool sixteen = max_value > 255;
  const size_t samples = static_cast<size_t>(width) * height * channels;
  if (samples > data.size() - pos) throw InputError(path, "Netpbm pixel data is truncated");
  cv::Mat image(height, width, CV_MAKETYPE(sixteen ? CV_16U : CV_8U, channels));
  std::vector<int> values(samples);
  if (ascii) {
    std::string token;
    for (size_t i = 0; i < samples; ++i) {
      if (!nextToken(data, &pos, &token)) throw InputError(path, "Netpbm pixel data is truncated");
      if (token.size() > 5 || !std::all_of(token.begin(), token.end(), [](char c) { return std::isdigit(c); }))
        throw InputError(path, "Netpbm pixel value '" + token + "' is not a number");
      values[i] = std::stoi(token);
    }
  } else {
    ++pos;  // the single white space character after maxval
    const size_t bytes = samples * (sixteen ? 2 : 1);
    if (pos > data.size() || data.size() - pos < bytes) throw InputError(path, "Netpbm pixel data is truncated");
    const auto* raw = reinterpret_cast<const unsigned char*>(data.data() + pos);
    for (size_t i = 0; i < samples; ++i) values[i] = sixteen ? (raw[2 * i] << 8) | raw[2 * i + 1] : raw[i];
  }
  size_t i = 0;
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c)
      for (int k = 0; k < channels; ++k, ++i) {
        const int value = std::min(values[i], max_value);
        const int channel = channels == 3 ? 2 - k : k;  // Netpbm stores RGB, OpenCV's layout is BGR
        if (sixteen) image.ptr<uint16_t>(r)[c * channels + channel] = static_cast<uint16_t>(value);
        else image.ptr<uint8_t>(r)[c * channels + channel] = static_cast<uint8_t>(value);
      }
  return image;
}

// libpng reports errors by longjmp: the functions below keep no C++ objects alive across it.
struct PngRows {
  png_uint_32 width, height;
  int bit_depth, colour_type;
  png_bytepp rows;  // BGR(A) order for colour, host byte order for 16 bits
};

void onPngError(png_structp png, png_const_charp message) {
  auto* error = static_cast<char*>(png_get_error_ptr(png));
  std::snprintf(error, 256, "%s", message);
  std::longjmp(png_jmpbuf(png), 1);
}

void onPngWarning(png_structp, png_const_charp) {}

bool writePngRows(std::FILE* file, const PngRows& image, char* error) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, error, onPngError, onPngWarning);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_init_io(png, file);
  png_set_compression_level(png, 1);  // fast, like OpenCV's default: maps compress well anyway
  // One filter for every row instead of libpng's per-row trial of all five: map, label and overlay images
  // repeat their rows, so "up" is 2-3 times faster than the trial at about the same size.
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_UP);
  png_set_IHDR(png, info, image.width, image.height, image.bit_depth, image.colour_type, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  if (image.colour_type & PNG_COLOR_MASK_COLOR) png_set_bgr(png);
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  if (image.bit_depth == 16) png_set_swap(png);  // PNG stores 16-bit samples big-endian
#endif
  png_write_image(png, image.rows);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

}  // namespace

cv::Mat readImage(const std::string& path) {
  if (isFolder(path)) throw InputError(path, "is a folder, not an image file");
  if (!isFile(path)) throw InputError(path, "image file does not exist");
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(path, "cannot open image file");
  unsigned char head[8] = {0};
  file.read(reinterpret_cast<char*>(head), sizeof(head));
  if (file.gcount() == sizeof(head) && std::memcmp(head, kPngSignature, sizeof(head)) == 0) return readPng(path);
  if (file.gcount() >= 2 && head[0] == 'P' && std::strchr("2356", head[1]) != nullptr) {
    // The header's size is checked on the file's first bytes, before a file of any length is read whole.
    file.clear();
    file.seekg(0);
    std::string head_bytes(kNetpbmHeaderBytes, '\0');
    file.read(head_bytes.data(), static_cast<std::streamsize>(head_bytes.size()));
    head_bytes.resize(static_cast<size_t>(file.gcount()));
    const size_t file_bytes = static_cast<size_t>(std::filesystem::file_size(path));
    checkNetpbmFileSize(path, head_bytes, file_bytes);
    file.clear();
    file.seekg(0);
    const std::string data((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    return readNetpbm(path, data);
  }
  throw InputError(path, "not a PNG, PGM or PPM image");
}

cv::Mat1b readGreyImage(const std::string& path) {
  const cv::Mat image = readImage(path);
  if (image.depth() != CV_8U) throw InputError(path, "is not an 8-bit image");
  cv::Mat1b grey;
  if (image.channels() == 1) grey = image;
  else if (image.channels() == 2) cv::extractChannel(image, grey, 0);  // grey + alpha
  else cv::cvtColor(image, grey, image.channels() == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
  return grey;
}

namespace {

// writeImage's work: errors name `path`, the bytes go to `file_path`.
void writeImageFile(const std::string& path, const std::string& file_path, const cv::Mat& image) {
  if (image.empty()) throw InputError(path, "cannot write an empty image");
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  const cv::Mat pixels = image.isContinuous() ? image : image.clone();
  if (extension == ".pgm") {
    if (pixels.type() != CV_8UC1 && pixels.type() != CV_16UC1)
      throw InputError(path, "a PGM holds 8- or 16-bit grey images only");
    const bool sixteen = pixels.depth() == CV_16U;
    std::ofstream file(file_path, std::ios::binary);
    file << "P5\n" << pixels.cols << " " << pixels.rows << "\n" << (sixteen ? 65535 : 255) << "\n";
    if (sixteen) {
      std::vector<unsigned char> bytes(pixels.total() * 2);
      const auto* values = pixels.ptr<uint16_t>();
      for (size_t i = 0; i < pixels.total(); ++i) bytes[2 * i] = values[i] >> 8, bytes[2 * i + 1] = values[i] & 0xff;
      file.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    } else {
      file.write(reinterpret_cast<const char*>(pixels.data), static_cast<std::streamsize>(pixels.total()));
    }
    file.close();
    if (!file) throw InputError(path, "cannot write image file");
    return;
  }
  if (extension != ".png") throw InputError(path, "cannot write images of type '" + extension + "' (use .png or .pgm)");
  int colour_type = 0;
  switch (pixels.channels()) {
    case 1: colour_type = PNG_COLOR_TYPE_GRAY; break;
    case 2: colour_type = PNG_COLOR_TYPE_GRAY_ALPHA; break;
    case 3: colour_type = PNG_COLOR_TYPE_RGB; break;
    case 4: colour_type = PNG_COLOR_TYPE_RGB_ALPHA; break;
  }
  if (pixels.depth() != CV_8U && pixels.depth() != CV_16U) throw InputError(path, "cannot write this pixel type as PNG");
  std::vector<png_bytep> rows(static_cast<size_t>(pixels.rows));
  for (int r = 0; r < pixels.rows; ++r) rows[static_cast<size_t>(r)] = const_cast<png_bytep>(pixels.ptr<png_byte>(r));
  PngRows png_rows{static_cast<png_uint_32>(pixels.cols), static_cast<png_uint_32>(pixels.rows),
                   pixels.depth() == CV_16U ? 16 : 8, colour_type, rows.data()};
  std::FILE* file = std::fopen(file_path.c_str(), "wb");
  if (file == nullptr) throw InputError(path, "cannot open image file for writing");
  char error[256] = "";
  const bool written = writePngRows(file, png_rows, error);
  const bool closed = std::fclose(file) == 0;
  if (!written || !closed) throw InputError(path, std::string("cannot write PNG: ") + (written ? "close failed" : error));
}

}  // namespace

void writeImage(const std::string& path, const cv::Mat& image) {
  writeAtomically(path, [&](const std::string& temporary) { writeImageFile(path, temporary, image); });
}

}  // namespace hidden_rooms::common
