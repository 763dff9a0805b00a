#pragma once
/// @file check_report.hpp
/// What `simreel check` reports about a run over several goldens: the outcome of each golden,
/// a JUnit XML file for CI systems (one test case per golden) and an HTML page with expected |
/// actual | difference images for every failing frame. Every file is written atomically.

#include <filesystem>
#include <string>
#include <vector>

#include "simreel/render/image.hpp"

namespace simreel::app {

/// One hashed frame out of tolerance.
struct FrameMismatch {
  int frame = 0;
  int distance[3] = {0, 0, 0};   ///< phash, dhash, chash Hamming distances
  int tolerance[3] = {0, 0, 0};
  int excess = 0;                ///< largest distance - tolerance over the three kinds
  /// The images of the report, relative to the report folder ("" when no report is written or
  /// the golden has no reference frame).
  std::string expected_png, actual_png, diff_png;
};

/// The outcome of checking one golden.
struct GoldenOutcome {
  enum class Status { passed, failed, error, updated };
  std::string golden;             ///< the path as given or found
  Status status = Status::error;
  double seconds = 0.0;
  int frames = 0;                 ///< hashed frames compared
  std::vector<FrameMismatch> mismatches;  ///< worst first
  std::string message;            ///< one line: the summary of a failure, or the error
  std::string details;            ///< the per-frame lines, for the JUnit body
};

/// expected | actual | difference (x4), labelled, at the expected frame's size; `expected`
/// may be null (no reference frame).
render::Image comparison_image(const render::Image* expected, const render::Image& actual);
/// The difference image (x4) of two images of the same size.
render::Image difference_image(const render::Image& expected, const render::Image& actual);

/// "1 passed, 2 failed" (", 1 error" when a golden could not be checked; ", 3 updated").
std::string summary_line(const std::vector<GoldenOutcome>& outcomes);

/// Writes a JUnit XML file: one <testsuite name="simreel check"> with one <testcase> per golden;
/// a mismatch is a <failure> naming the worst frame and its distances, a bad golden an <error>.
/// @throws render::IoError naming the path.
void write_junit(const std::filesystem::path& path, const std::vector<GoldenOutcome>& outcomes);

/// Writes `dir`/index.html: the summary, then for every failing golden a table of its failing
/// frames with the expected, actual and difference images (written beforehand by the check).
/// @throws render::IoError naming the path.
void write_html_report(const std::filesystem::path& dir, const std::vector<GoldenOutcome>& outcomes);

/// A folder name for a golden's report images: its path with separators as '_' ("tests_golden_rain").
std::string report_folder_name(const std::string& golden);

}  // namespace simreel::app
