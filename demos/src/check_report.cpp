#include "check_report.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "simreel/render/atomic_file.hpp"
#include "simreel/render/text_overlay.hpp"

namespace simreel::app {

namespace fs = std::filesystem;

render::Image difference_image(const render::Image& expected, const render::Image& actual) {
  render::Image diff(expected.width, expected.height);
  for (std::size_t i = 0; i < diff.rgba.size(); i += 4) {
    for (std::size_t c = 0; c < 3; ++c) {
      const int d = std::abs(int(expected.rgba[i + c]) - int(actual.rgba[i + c]));
      diff.rgba[i + c] = std::uint8_t(std::min(255, 4 * d));
    }
    diff.rgba[i + 3] = 255;
  }
  return diff;
}

render::Image comparison_image(const render::Image* expected, const render::Image& actual_full) {
  const int w = expected != nullptr ? expected->width : actual_full.width;
  const int h = expected != nullptr ? expected->height : actual_full.height;
  const render::Image actual =
      actual_full.width == w && actual_full.height == h ? actual_full : render::resize_box(actual_full, w, h);
  render::Image out(3 * w + 8, h);
  for (std::size_t i = 0; i < out.rgba.size(); i += 4) {
    out.rgba[i] = out.rgba[i + 1] = out.rgba[i + 2] = 40;
    out.rgba[i + 3] = 255;
  }
  if (expected != nullptr) {
    render::blit(out, *expected, 0, 0);
    render::blit(out, difference_image(*expected, actual), 2 * w + 8, 0);
  }
  render::blit(out, actual, w + 4, 0);
  render::TextStyle style;
  style.scale = std::max(1, h / 180);
  render::draw_text(out, 0, 0, expected != nullptr ? "expected" : "expected: no reference frame", style);
  render::draw_text(out, w + 4, 0, "actual", style);
  render::draw_text(out, 2 * w + 8, 0, "difference x4", style);
  return out;
}

std::string summary_line(const std::vector<GoldenOutcome>& outcomes) {
  int count[4] = {0, 0, 0, 0};
  for (const auto& o : outcomes) ++count[int(o.status)];
  using S = GoldenOutcome::Status;
  std::string line = std::to_string(count[int(S::passed)]) + " passed, " + std::to_string(count[int(S::failed)]) +
                     " failed";
  if (count[int(S::error)] > 0)
    line += ", " + std::to_string(count[int(S::error)]) + (count[int(S::error)] == 1 ? " error" : " errors");
  if (count[int(S::updated)] > 0) line += ", " + std::to_string(count[int(S::updated)]) + " updated";
  return line;
}

namespace {

/// Escapes text for XML/HTML content and attribute values.
std::string escape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default:
        // Control characters other than tab and newline are not allowed in XML 1.0.
        if (static_cast<unsigned char>(c) < 0x20 && c != '\n' && c != '\t') out += '?';
        else out += c;
    }
  }
  return out;
}

std::string seconds_text(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", s);
  return buf;
}

}  // namespace

void write_junit(const fs::path& path, const std::vector<GoldenOutcome>& outcomes) {
  using S = GoldenOutcome::Status;
  int failures = 0, errors = 0;
  double total = 0.0;
  for (const auto& o : outcomes) {
    failures += o.status == S::failed ? 1 : 0;
    errors += o.status == S::error ? 1 : 0;
    total += o.seconds;
  }
  std::ostringstream x;
  const std::string counts = "tests=\"" + std::to_string(outcomes.size()) + "\" failures=\"" +
                             std::to_string(failures) + "\" errors=\"" + std::to_string(errors) + "\" time=\"" +
                             seconds_text(total) + "\"";
  x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  x << "<testsuites name=\"simreel check\" " << counts << ">\n";
  x << "  <testsuite name=\"simreel check\" " << counts << ">\n";
  for (const auto& o : outcomes) {
    x << "    <testcase classname=\"simreel.check\" name=\"" << escape(o.golden) << "\" time=\""
      << seconds_text(o.seconds) << "\"";
    if (o.status == S::failed) {
      x << ">\n      <failure type=\"mismatch\" message=\"" << escape(o.message) << "\">" << escape(o.details)
        << "</failure>\n    </testcase>\n";
    } else if (o.status == S::error) {
      x << ">\n      <error type=\"bad input\" message=\"" << escape(o.message) << "\">" << escape(o.details)
        << "</error>\n    </testcase>\n";
    } else {
      x << "/>\n";
    }
  }
  x << "  </testsuite>\n</testsuites>\n";
  render::write_file_atomic(path, x.str());
}

void write_html_report(const fs::path& dir, const std::vector<GoldenOutcome>& outcomes) {
  using S = GoldenOutcome::Status;
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
    << "<title>simreel check: " << escape(summary_line(outcomes)) << "</title>\n"
    << "<style>body{font-family:sans-serif;background:#f4f4f4;margin:1.5em}"
       "table{border-collapse:collapse;margin-bottom:2em}td,th{padding:4px 8px;vertical-align:top;text-align:left}"
       "img{image-rendering:pixelated;border:1px solid #999;max-width:480px}"
       ".passed{color:#176f2c}.failed{color:#b00020}.error{color:#8a4b00}.updated{color:#1a4f9c}</style>\n"
    << "</head>\n<body>\n<h1>simreel check</h1>\n<p>" << escape(summary_line(outcomes)) << "</p>\n<table>\n"
    << "<tr><th>golden</th><th>result</th><th>frames</th><th>time (s)</th><th></th></tr>\n";
  const char* names[] = {"passed", "failed", "error", "updated"};
  for (const auto& o : outcomes) {
    h << "<tr><td>";
    if (o.status == S::failed) h << "<a href=\"#" << escape(report_folder_name(o.golden)) << "\">";
    h << escape(o.golden) << (o.status == S::failed ? "</a>" : "") << "</td><td class=\"" << names[int(o.status)]
      << "\">" << names[int(o.status)] << "</td><td>" << o.frames << "</td><td>" << seconds_text(o.seconds)
      << "</td><td>" << escape(o.message) << "</td></tr>\n";
  }
  h << "</table>\n";
  for (const auto& o : outcomes) {
    if (o.status != S::failed) continue;
    h << "<h2 id=\"" << escape(report_folder_name(o.golden)) << "\">" << escape(o.golden) << "</h2>\n<p>"
      << escape(o.message) << "</p>\n<table>\n"
      << "<tr><th>frame</th><th>expected (reference frame)</th><th>actual</th><th>difference &times;4</th></tr>\n";
    for (const auto& m : o.mismatches) {
      h << "<tr><td>" << m.frame << "<br>phash " << m.distance[0] << "/" << m.tolerance[0] << "<br>dhash "
        << m.distance[1] << "/" << m.tolerance[1] << "<br>chash " << m.distance[2] << "/" << m.tolerance[2]
        << "</td>";
      for (const std::string* img : {&m.expected_png, &m.actual_png, &m.diff_png}) {
        if (img->empty()) h << "<td>no reference frame (record one with <code>check --update</code>)</td>";
        else h << "<td><img src=\"" << escape(*img) << "\" alt=\"" << escape(*img) << "\"></td>";
      }
      h << "</tr>\n";
    }
    h << "</table>\n";
  }
  h << "</body>\n</html>\n";
  render::write_file_atomic(dir / "index.html", h.str());
}

std::string report_folder_name(const std::string& golden) {
  std::string name = fs::path(golden).lexically_normal().replace_extension("").generic_string();
  for (char& c : name) {
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-';
    if (!plain) c = '_';
  }
  while (!name.empty() && name.front() == '_') name.erase(name.begin());
  return name.empty() ? "golden" : name;
}

}  // namespace simreel::app
