#pragma once
// The "error against run time" report as one self-contained HTML page: per section an inline SVG
// plot of PSNR against milliseconds (log scale) with the Pareto front, a table and pictures.
// No scripts, no network.
#include <cstddef>
#include <string>
#include <vector>

#include "reprise/core/status.hpp"

namespace reprise::cli {

struct ReportPoint {
    std::string method;   // points of one method share a colour
    std::string setting;  // the label beside the point
    double psnr = 0.0, ssim = 0.0, flip = 0.0, ms = 0.0;
};

struct ReportImage {
    std::string file;  // relative to the page
    std::string caption;
};

struct ReportSection {
    std::string title;
    std::string note;  // plain text under the title
    std::string html;  // markup from the plot helpers below, placed under the note
    // The error-against-time plot and table; none when empty.
    std::vector<ReportPoint> points;
    std::string time_label = "ms per synthesized frame (log scale)";  // its x axis
    std::vector<ReportImage> images;
};

struct Report {
    std::string title;
    std::vector<std::string> paragraphs;  // plain text above the sections
    std::string preformatted;             // e.g. the summary table; empty = none
    std::vector<ReportSection> sections;
};

// Points no other point beats in both (at most the time, at least the PSNR, one strictly),
// by increasing time; points with a NaN or non-positive time or a NaN PSNR are left out.
std::vector<std::size_t> pareto_front(const std::vector<ReportPoint>& points);

// PSNR (y) against ms (x, log scale), every point labelled, the Pareto front as a staircase.
std::string error_time_svg(const std::vector<ReportPoint>& points,
                           const std::string& time_label = "ms per synthesized frame (log scale)");

// Curves of y against x (e.g. PSNR against bits), one colour per series, points joined in the
// order given; NaN and infinite points are left out.
struct PlotSeries {
    std::string name;
    std::vector<double> x, y;
    bool dashed = false;
};
struct PlotAxes {
    std::string x_label, y_label;
    bool log_x = true;
};
std::string line_plot_svg(const std::vector<PlotSeries>& series, const PlotAxes& axes);

// Horizontal bars: per row a label and one bar per value (values[i] named by value_names[i]).
struct BarRow {
    std::string label;
    std::vector<double> values;
};
std::string bar_chart_svg(const std::vector<BarRow>& rows,
                          const std::vector<std::string>& value_names, const std::string& unit);

Status write_html_report(const std::string& path, const Report& report);

}  // namespace reprise::cli
