#include "report_html.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <utility>

namespace reprise::cli {

namespace {

std::string escape(const std::string& text) {
    std::string out;
    for (char c : text) {
        switch (c) {
            case '&':
                out += "&amp;";
                break;
            case '<':
                out += "&lt;";
                break;
            case '>':
                out += "&gt;";
                break;
            case '"':
                out += "&quot;";
                break;
            default:
                out += c;
        }
    }
    return out;
}

std::string format(const char* pattern, double value) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, pattern, value);
    return buffer;
}

const char* method_color(std::size_t index) {
    static const char* palette[] = {"#1f6fb4", "#e8790c", "#2a9d3a", "#c9302c",
                                    "#7b52ab", "#8c5a3c", "#d4429b", "#6b6b6b"};
    return palette[index % (sizeof palette / sizeof *palette)];
}

struct Box {
    double x0, y0, x1, y1;
    bool overlaps(const Box& o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
};

// A 1-2-5 step giving about `count` intervals over `range`.
double nice_step(double range, int count) {
    double raw = range / count, decade = std::pow(10.0, std::floor(std::log10(raw)));
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * decade >= raw) return m * decade;
    return 10.0 * decade;
}

// The largest 1-2-5 value (..., 0.5, 1, 2, 5, 10, ...) at most `v`, or the smallest above it.
double step_125(double v, bool up) {
    double decade = std::pow(10.0, std::floor(std::log10(v)));
    if (!up) {
        for (double m : {5.0, 2.0, 1.0})
            if (m * decade <= v) return m * decade;
        return decade;
    }
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * decade > v) return m * decade;
    return 10.0 * decade;
}

}  // namespace

std::vector<std::size_t> pareto_front(const std::vector<ReportPoint>& points) {
    std::vector<std::size_t> order;
    for (std::size_t i = 0; i < points.size(); ++i)
        if (points[i].ms > 0.0 && !std::isnan(points[i].psnr)) order.push_back(i);
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        if (points[a].ms != points[b].ms) return points[a].ms < points[b].ms;
        return points[a].psnr > points[b].psnr;
    });
    std::vector<std::size_t> front;
    for (std::size_t i : order)
        if (front.empty() || points[i].psnr > points[front.back()].psnr) front.push_back(i);
    return front;
}

std::string error_time_svg(const std::vector<ReportPoint>& points, const std::string& time_label) {
    const double width = 760, height = 460, left = 64, right = 24, top = 20, bottom = 84;
    const double plot_w = width - left - right, plot_h = height - top - bottom;
    std::vector<std::size_t> shown;
    double ms_lo = INFINITY, ms_hi = -INFINITY, db_lo = INFINITY, db_hi = -INFINITY;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const ReportPoint& p = points[i];
        if (!(p.ms > 0.0) || !std::isfinite(p.ms) || std::isnan(p.psnr)) continue;
        shown.push_back(i);
        ms_lo = std::min(ms_lo, p.ms), ms_hi = std::max(ms_hi, p.ms);
        if (std::isfinite(p.psnr)) db_lo = std::min(db_lo, p.psnr), db_hi = std::max(db_hi, p.psnr);
    }
    if (shown.empty()) ms_lo = 1, ms_hi = 10;
    if (!(db_lo <= db_hi)) db_lo = 20, db_hi = 40;
    // The x range ends on 1-2-5 ticks just outside the data.
    const double x_lo = std::log10(step_125(ms_lo, false)),
                 x_hi = std::log10(step_125(ms_hi * 1.0001, true));
    const double step = nice_step(std::max(db_hi - db_lo, 1.0), 6);
    const double y_lo = std::floor((db_lo - 0.3 * step) / step) * step;
    const double y_hi = std::ceil((db_hi + 0.3 * step) / step) * step;
    auto px = [&](double ms) { return left + (std::log10(ms) - x_lo) / (x_hi - x_lo) * plot_w; };
    auto py = [&](double db) {
        db = std::clamp(db, y_lo, y_hi);  // +inf (identical frames) sits on the top edge
        return top + (y_hi - db) / (y_hi - y_lo) * plot_h;
    };

    std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + format("%.0f", width) +
                      "\" height=\"" + format("%.0f", height) + "\" viewBox=\"0 0 " +
                      format("%.0f", width) + " " + format("%.0f", height) +
                      "\" font-family=\"sans-serif\" font-size=\"11\">\n";
    svg += "<rect x=\"" + format("%.1f", left) + "\" y=\"" + format("%.1f", top) + "\" width=\"" +
           format("%.1f", plot_w) + "\" height=\"" + format("%.1f", plot_h) +
           "\" fill=\"#fafafa\" stroke=\"#888\"/>\n";
    // Grid and ticks: 1, 2, 5 per decade on x; a 1-2-5 step on y.
    for (double d = std::floor(x_lo); d <= x_hi; ++d)
        for (double m : {1.0, 2.0, 5.0}) {
            double ms = m * std::pow(10.0, d), x = px(ms);
            if (std::log10(ms) < x_lo - 1e-9 || std::log10(ms) > x_hi + 1e-9) continue;
            svg += "<line x1=\"" + format("%.1f", x) + "\" y1=\"" + format("%.1f", top) +
                   "\" x2=\"" + format("%.1f", x) + "\" y2=\"" + format("%.1f", top + plot_h) +
                   "\" stroke=\"" + (m == 1.0 ? "#ccc" : "#eee") + "\"/>\n";
            svg += "<text x=\"" + format("%.1f", x) + "\" y=\"" +
                   format("%.1f", top + plot_h + 14) + "\" text-anchor=\"middle\">" +
                   format("%g", ms) + "</text>\n";
        }
    for (double db = y_lo; db <= y_hi + 1e-9; db += step) {
        double y = py(db);
        svg += "<line x1=\"" + format("%.1f", left) + "\" y1=\"" + format("%.1f", y) + "\" x2=\"" +
               format("%.1f", left + plot_w) + "\" y2=\"" + format("%.1f", y) +
               "\" stroke=\"#e4e4e4\"/>\n";
        svg += "<text x=\"" + format("%.1f", left - 6) + "\" y=\"" + format("%.1f", y + 4) +
               "\" text-anchor=\"end\">" + format("%g", db) + "</text>\n";
    }
    svg += "<text x=\"" + format("%.1f", left + plot_w / 2) + "\" y=\"" +
           format("%.1f", top + plot_h + 32) + "\" text-anchor=\"middle\">" + escape(time_label) +
           "</text>\n";
    svg += "<text transform=\"translate(16 " + format("%.1f", top + plot_h / 2) +
           ") rotate(-90)\" text-anchor=\"middle\">PSNR, dB (higher is better)</text>\n";

    std::vector<std::string> methods;
    for (std::size_t i : shown)
        if (std::find(methods.begin(), methods.end(), points[i].method) == methods.end())
            methods.push_back(points[i].method);
    auto color_of = [&](const std::string& method) {
        return method_color(
            std::size_t(std::find(methods.begin(), methods.end(), method) - methods.begin()));
    };

    std::vector<std::size_t> front = pareto_front(points);
    if (!front.empty()) {
        std::string path = "M" + format("%.1f", px(points[front[0]].ms)) + " " +
                           format("%.1f", py(points[front[0]].psnr));
        for (std::size_t k = 1; k < front.size(); ++k)
            path += " H" + format("%.1f", px(points[front[k]].ms)) + " V" +
                    format("%.1f", py(points[front[k]].psnr));
        path += " H" + format("%.1f", left + plot_w);
        svg += "<path d=\"" + path +
               "\" fill=\"none\" stroke=\"#222\" stroke-width=\"1.5\" "
               "stroke-dasharray=\"5 3\"/>\n";
    }

    std::vector<Box> taken;
    for (std::size_t i : shown) {
        const ReportPoint& p = points[i];
        double x = px(p.ms), y = py(p.psnr);
        taken.push_back({x - 7, y - 7, x + 7, y + 7});
    }
    for (std::size_t i : shown) {
        const ReportPoint& p = points[i];
        const double x = px(p.ms), y = py(p.psnr);
        const bool on_front = std::find(front.begin(), front.end(), i) != front.end();
        svg += "<g><title>" + escape(p.method + " " + p.setting) + ": " +
               format("%.2f dB", p.psnr) + ", " + format("%.3g ms", p.ms) +
               (on_front ? " (Pareto front)" : "") + "</title>";
        if (on_front)
            svg += "<circle cx=\"" + format("%.1f", x) + "\" cy=\"" + format("%.1f", y) +
                   "\" r=\"7\" fill=\"none\" stroke=\"#222\" stroke-width=\"1.5\"/>";
        svg += "<circle cx=\"" + format("%.1f", x) + "\" cy=\"" + format("%.1f", y) +
               "\" r=\"4\" fill=\"" + color_of(p.method) + "\"/></g>\n";
        // The label goes where it covers the least of the other points and labels: beside,
        // above, below or diagonal to its point, then twice as far out.
        const double text_w = 6.0 * double(p.setting.size()), text_h = 11;
        Box chosen{};
        double least = INFINITY;
        for (double gap : {10.0, 24.0})  // 10 clears the front marker's ring
            for (auto [dx, dy] :
                 {std::pair{1, 0}, {-1, 0}, {0, -1}, {0, 1}, {1, -1}, {1, 1}, {-1, -1}, {-1, 1}}) {
                const double cx = dx > 0 ? x + gap : dx < 0 ? x - gap - text_w : x - text_w / 2;
                const double cy = dy > 0 ? y + gap : dy < 0 ? y - gap - text_h : y - text_h / 2;
                const Box c{cx, cy, cx + text_w, cy + text_h};
                if (c.x0 < 0 || c.x1 > width || c.y0 < 0 || c.y1 > top + plot_h) continue;
                double covered = 0.0;
                for (const Box& t : taken)
                    if (c.overlaps(t))
                        covered += (std::min(c.x1, t.x1) - std::max(c.x0, t.x0)) *
                                   (std::min(c.y1, t.y1) - std::max(c.y0, t.y0));
                if (covered < least) least = covered, chosen = c;
                if (covered == 0.0) break;
            }
        if (!std::isfinite(least))
            chosen = {x + 10, y - text_h / 2, x + 10 + text_w, y + text_h / 2};
        taken.push_back(chosen);
        svg += "<text x=\"" + format("%.1f", chosen.x0) + "\" y=\"" +
               format("%.1f", chosen.y1 - 2) + "\" font-size=\"10\" fill=\"" + color_of(p.method) +
               "\" stroke=\"#fafafa\" stroke-width=\"3\" paint-order=\"stroke\">" +
               escape(p.setting) + "</text>\n";
    }

    double lx = left;
    const double ly = top + plot_h + 56;
    for (const std::string& m : methods) {
        svg += "<circle cx=\"" + format("%.1f", lx + 5) + "\" cy=\"" + format("%.1f", ly - 4) +
               "\" r=\"4\" fill=\"" + color_of(m) + "\"/><text x=\"" + format("%.1f", lx + 13) +
               "\" y=\"" + format("%.1f", ly) + "\">" + escape(m) + "</text>\n";
        lx += 30 + 6.5 * double(m.size());
    }
    svg += "<path d=\"M" + format("%.1f", lx) + " " + format("%.1f", ly - 4) +
           " h24\" stroke=\"#222\" "
           "stroke-width=\"1.5\" stroke-dasharray=\"5 3\"/><text x=\"" +
           format("%.1f", lx + 30) + "\" y=\"" + format("%.1f", ly) +
           "\">Pareto front (best PSNR for the time)</text>\n";
    svg += "</svg>\n";
    return svg;
}

std::string line_plot_svg(const std::vector<PlotSeries>& series, const PlotAxes& axes) {
    const double width = 760, height = 420, left = 64, right = 24, top = 20;
    const double legend_rows = double((series.size() + 3) / 4);
    const double bottom = 48 + 16 * legend_rows;
    const double plot_w = width - left - right, plot_h = height - top - bottom;
    auto xv = [&](double x) { return axes.log_x ? std::log10(x) : x; };
    auto usable = [&](double x, double y) {
        return std::isfinite(x) && std::isfinite(y) && (!axes.log_x || x > 0.0);
    };
    double x_lo = INFINITY, x_hi = -INFINITY, y_lo = INFINITY, y_hi = -INFINITY;
    for (const PlotSeries& s : series)
        for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
            if (usable(s.x[i], s.y[i])) {
                x_lo = std::min(x_lo, xv(s.x[i])), x_hi = std::max(x_hi, xv(s.x[i]));
                y_lo = std::min(y_lo, s.y[i]), y_hi = std::max(y_hi, s.y[i]);
            }
    if (!(x_lo <= x_hi)) x_lo = 0, x_hi = 1;
    if (!(y_lo <= y_hi)) y_lo = 0, y_hi = 1;
    if (axes.log_x) x_lo = std::floor(x_lo * 4) / 4, x_hi = std::ceil(x_hi * 4) / 4;
    if (x_hi - x_lo < 1e-9) x_lo -= 0.5, x_hi += 0.5;
    const double y_step = nice_step(std::max(y_hi - y_lo, 1e-6), 6);
    y_lo = std::floor(y_lo / y_step) * y_step, y_hi = std::ceil(y_hi / y_step) * y_step;
    if (y_hi - y_lo < 1e-12) y_hi = y_lo + y_step;
    auto px = [&](double x) { return left + (xv(x) - x_lo) / (x_hi - x_lo) * plot_w; };
    auto py = [&](double y) { return top + (y_hi - y) / (y_hi - y_lo) * plot_h; };
    std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + format("%.0f", width) +
                      "\" height=\"" + format("%.0f", height) +
                      "\" font-family=\"sans-serif\" "
                      "font-size=\"11\">\n<rect x=\"" +
                      format("%.1f", left) + "\" y=\"" + format("%.1f", top) + "\" width=\"" +
                      format("%.1f", plot_w) + "\" height=\"" + format("%.1f", plot_h) +
                      "\" fill=\"#fafafa\" stroke=\"#888\"/>\n";
    auto vline = [&](double x, const char* color) {
        svg += "<line x1=\"" + format("%.1f", x) + "\" y1=\"" + format("%.1f", top) + "\" x2=\"" +
               format("%.1f", x) + "\" y2=\"" + format("%.1f", top + plot_h) + "\" stroke=\"" +
               color + "\"/>\n";
    };
    if (axes.log_x) {
        for (double d = std::floor(x_lo); d <= x_hi; ++d)
            for (double m : {1.0, 2.0, 5.0}) {
                const double v = m * std::pow(10.0, d);
                if (std::log10(v) < x_lo - 1e-9 || std::log10(v) > x_hi + 1e-9) continue;
                vline(px(v), m == 1.0 ? "#ccc" : "#eee");
                svg += "<text x=\"" + format("%.1f", px(v)) + "\" y=\"" +
                       format("%.1f", top + plot_h + 14) + "\" text-anchor=\"middle\">" +
                       format("%g", v) + "</text>\n";
            }
    } else {
        const double step = nice_step(x_hi - x_lo, 8);
        for (double v = std::ceil(x_lo / step) * step; v <= x_hi + 1e-9; v += step) {
            vline(px(v), "#e4e4e4");
            svg += "<text x=\"" + format("%.1f", px(v)) + "\" y=\"" +
                   format("%.1f", top + plot_h + 14) + "\" text-anchor=\"middle\">" +
                   format("%g", v) + "</text>\n";
        }
    }
    for (double v = y_lo; v <= y_hi + 1e-9 * y_step; v += y_step) {
        svg += "<line x1=\"" + format("%.1f", left) + "\" y1=\"" + format("%.1f", py(v)) +
               "\" x2=\"" + format("%.1f", left + plot_w) + "\" y2=\"" + format("%.1f", py(v)) +
               "\" stroke=\"#e4e4e4\"/>\n<text x=\"" + format("%.1f", left - 6) + "\" y=\"" +
               format("%.1f", py(v) + 4) + "\" text-anchor=\"end\">" + format("%g", v) +
               "</text>\n";
    }
    svg += "<text x=\"" + format("%.1f", left + plot_w / 2) + "\" y=\"" +
           format("%.1f", top + plot_h + 30) + "\" text-anchor=\"middle\">" + escape(axes.x_label) +
           (axes.log_x ? " (log scale)" : "") + "</text>\n";
    svg += "<text transform=\"translate(16 " + format("%.1f", top + plot_h / 2) +
           ") rotate(-90)\" text-anchor=\"middle\">" + escape(axes.y_label) + "</text>\n";
    for (std::size_t k = 0; k < series.size(); ++k) {
        const PlotSeries& s = series[k];
        const char* color = method_color(k);
        std::string path;
        std::string dots;
        for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
            if (!usable(s.x[i], s.y[i])) continue;
            const double x = px(s.x[i]), y = py(s.y[i]);
            path += (path.empty() ? "M" : " L") + format("%.1f", x) + " " + format("%.1f", y);
            dots += "<circle cx=\"" + format("%.1f", x) + "\" cy=\"" + format("%.1f", y) +
                    "\" r=\"3\" fill=\"" + color + "\"><title>" + escape(s.name) + ": " +
                    format("%.4g", s.x[i]) + ", " + format("%.4g", s.y[i]) + "</title></circle>";
        }
        svg += "<path d=\"" + path + "\" fill=\"none\" stroke=\"" + color +
               "\" stroke-width=\"1.5\"" + (s.dashed ? " stroke-dasharray=\"5 3\"" : "") + "/>" +
               dots + "\n";
        const double lx = left + double(k % 4) * (plot_w / 4);
        const double ly = top + plot_h + 48 + 16 * double(k / 4);
        svg += "<path d=\"M" + format("%.1f", lx) + " " + format("%.1f", ly - 4) +
               " h18\" stroke=\"" + color + "\" stroke-width=\"2\"" +
               (s.dashed ? " stroke-dasharray=\"5 3\"" : "") + "/><text x=\"" +
               format("%.1f", lx + 22) + "\" y=\"" + format("%.1f", ly) + "\">" + escape(s.name) +
               "</text>\n";
    }
    svg += "</svg>\n";
    return svg;
}

std::string bar_chart_svg(const std::vector<BarRow>& rows,
                          const std::vector<std::string>& value_names, const std::string& unit) {
    const std::size_t bars = std::max<std::size_t>(1, value_names.size());
    const double label_w = 230, width = 760, bar_h = 11, row_h = bar_h * double(bars) + 8;
    const double top = 24, plot_w = width - label_w - 90;
    const double height = top + row_h * double(rows.size()) + 28;
    double hi = 0.0;
    for (const BarRow& r : rows)
        for (double v : r.values)
            if (std::isfinite(v)) hi = std::max(hi, v);
    if (!(hi > 0.0)) hi = 1.0;
    std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + format("%.0f", width) +
                      "\" height=\"" + format("%.0f", height) +
                      "\" font-family=\"sans-serif\" font-size=\"11\">\n";
    double lx = label_w;
    for (std::size_t b = 0; b < value_names.size(); ++b) {
        svg += "<rect x=\"" + format("%.1f", lx) + "\" y=\"6\" width=\"10\" height=\"10\" fill=\"" +
               method_color(b) + "\"/><text x=\"" + format("%.1f", lx + 14) + "\" y=\"15\">" +
               escape(value_names[b]) + " (" + escape(unit) + ")</text>\n";
        lx += 40 + 6.5 * double(value_names[b].size() + unit.size());
    }
    for (std::size_t r = 0; r < rows.size(); ++r) {
        const double y0 = top + row_h * double(r);
        svg += "<text x=\"" + format("%.1f", label_w - 6) + "\" y=\"" +
               format("%.1f", y0 + row_h / 2 + 3) + "\" text-anchor=\"end\">" +
               escape(rows[r].label) + "</text>\n";
        for (std::size_t b = 0; b < rows[r].values.size(); ++b) {
            const double v = rows[r].values[b];
            if (!std::isfinite(v)) continue;
            const double y = y0 + 4 + bar_h * double(b), w = std::max(1.0, v / hi * plot_w);
            svg += "<rect x=\"" + format("%.1f", label_w) + "\" y=\"" + format("%.1f", y) +
                   "\" width=\"" + format("%.1f", w) + "\" height=\"" + format("%.1f", bar_h - 1) +
                   "\" fill=\"" + method_color(b) + "\"/><text x=\"" +
                   format("%.1f", label_w + w + 4) + "\" y=\"" + format("%.1f", y + bar_h - 2) +
                   "\" font-size=\"10\">" + format("%.3g", v) + "</text>\n";
        }
    }
    svg += "</svg>\n";
    return svg;
}

Status write_html_report(const std::string& path, const Report& report) {
    std::string html =
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" +
        escape(report.title) +
        "</title>\n<style>body{font-family:sans-serif;margin:2em;max-width:1100px;color:#222}"
        "table{border-collapse:collapse;font-size:13px;margin:1em 0}"
        "td,th{border:1px solid #ccc;padding:2px 8px;text-align:right}"
        "td:nth-child(-n+2),th:nth-child(-n+2){text-align:left}"
        "tr.front td{font-weight:bold}pre{background:#f4f4f4;padding:1em;overflow-x:auto}"
        "figure{margin:1em 0}img{max-width:100%;image-rendering:pixelated}"
        "figcaption{font-size:13px;color:#555}</style></head><body>\n<h1>" +
        escape(report.title) + "</h1>\n";
    for (const std::string& p : report.paragraphs) html += "<p>" + escape(p) + "</p>\n";
    if (!report.preformatted.empty()) html += "<pre>" + escape(report.preformatted) + "</pre>\n";
    for (const ReportSection& section : report.sections) {
        html += "<h2>" + escape(section.title) + "</h2>\n";
        if (!section.note.empty()) html += "<p>" + escape(section.note) + "</p>\n";
        html += section.html;
        if (!section.points.empty()) html += error_time_svg(section.points, section.time_label);
        std::vector<std::size_t> front = pareto_front(section.points);
        if (!section.points.empty())
            html +=
                "<table><tr><th>method</th><th>setting</th><th>PSNR dB</th><th>SSIM</th>"
                "<th>FLIP</th><th>ms</th><th>Pareto</th></tr>\n";
        for (std::size_t i = 0; i < section.points.size(); ++i) {
            const ReportPoint& p = section.points[i];
            const bool on_front = std::find(front.begin(), front.end(), i) != front.end();
            html += std::string(on_front ? "<tr class=\"front\">" : "<tr>") + "<td>" +
                    escape(p.method) + "</td><td>" + escape(p.setting) + "</td><td>" +
                    format("%.2f", p.psnr) + "</td><td>" + format("%.4f", p.ssim) + "</td><td>" +
                    format("%.4f", p.flip) + "</td><td>" + format("%.3g", p.ms) + "</td><td>" +
                    (on_front ? "front" : "") + "</td></tr>\n";
        }
        if (!section.points.empty()) html += "</table>\n";
        for (const ReportImage& image : section.images)
            html += "<figure><img src=\"" + escape(image.file) + "\" alt=\"" +
                    escape(image.caption) + "\"><figcaption>" + escape(image.caption) +
                    "</figcaption></figure>\n";
    }
    html += "</body></html>\n";
    std::ofstream file(path, std::ios::binary);
    file << html;
    file.close();
    if (!file) return Status::error(path + ": cannot write the report");
    return {};
}

}  // namespace reprise::cli
