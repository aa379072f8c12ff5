#pragma once
// Image files of the package (maps, label images, overlays, debug pictures) on libpng and a Netpbm reader and
// writer, so that the tools do not load OpenCV's imgcodecs with its long chain of codec libraries (most of a short
// command's run time). Pixel layouts follow cv::imread(..., cv::IMREAD_UNCHANGED): grey CV_8UC1 / CV_16UC1,
// grey + alpha CV_8UC2, colour BGR CV_8UC3 / CV_16UC3, BGRA CV_8UC4.
#include <string>

#include <opencv2/core.hpp>

namespace hidden_rooms::common {

// Reads a PNG (any bit depth, palette images as BGR; 16-bit images with alpha are reduced to 8 bits) or a
// Netpbm PGM / PPM (P2, P3, P5, P6; maxval above 255 gives 16 bits), chosen by the file's magic bytes.
// Throws InputError naming the file: missing, unreadable, not one of these formats, truncated, empty.
cv::Mat readImage(const std::string& path);
// The same, as 8-bit grey: colour by its luma, an alpha channel dropped. Throws InputError also for 16-bit images.
cv::Mat1b readGreyImage(const std::string& path);

// Writes a PNG (extension .png: CV_8UC1, CV_16UC1, CV_8UC2, CV_8UC3 BGR, CV_8UC4 BGRA, CV_16UC3) or a binary PGM
// (extension .pgm: CV_8UC1, CV_16UC1). Throws InputError naming the file when the extension or pixel type is not
// supported or the file cannot be written.
void writeImage(const std::string& path, const cv::Mat& image);

}  // namespace hidden_rooms::common
