// The built-in HUD: a UI layer drawn on the CPU after the 3-D pass.
#include <algorithm>
#include <cmath>

#include "reprise/server/builtin_scenes.hpp"

namespace reprise::server {

namespace {

// Premultiplied `paint` over the pixels of [x0, x1) x [y0, y1) (clipped).
void fill(Image<glm::vec4>& ui, int x0, int y0, int x1, int y1, glm::vec4 paint) {
    x0 = std::max(x0, 0), y0 = std::max(y0, 0);
    x1 = std::min(x1, ui.width()), y1 = std::min(y1, ui.height());
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) ui(x, y) = paint + (1.0f - paint.a) * ui(x, y);
}

// A seven-segment digit in a cell w wide and 2w tall, segments t thick.
void digit(Image<glm::vec4>& ui, int value, int x, int y, int w, int t, glm::vec4 paint) {
    static constexpr unsigned char kSegments[10] = {0x3f, 0x06, 0x5b, 0x4f, 0x66,
                                                    0x6d, 0x7d, 0x07, 0x7f, 0x6f};
    const unsigned bits = kSegments[value % 10];
    const int h = 2 * w;
    if (bits & 0x01) fill(ui, x, y, x + w, y + t, paint);                  // top
    if (bits & 0x02) fill(ui, x + w - t, y, x + w, y + h / 2, paint);      // upper right
    if (bits & 0x04) fill(ui, x + w - t, y + h / 2, x + w, y + h, paint);  // lower right
    if (bits & 0x08) fill(ui, x, y + h - t, x + w, y + h, paint);          // bottom
    if (bits & 0x10) fill(ui, x, y + h / 2, x + t, y + h, paint);          // lower left
    if (bits & 0x20) fill(ui, x, y, x + t, y + h / 2, paint);              // upper left
    if (bits & 0x40) fill(ui, x, y + h / 2 - t / 2, x + w, y + h / 2 + (t + 1) / 2, paint);  // mid
}

}  // namespace

void draw_hud(double time, int width, int height, Image<glm::vec4>& ui) {
    ui.assign(width, height, glm::vec4(0.0f));
    const float unit = float(height) / 360.0f;
    auto px = [unit](float v) { return int(std::lround(v * unit)); };
    const long tick = long(std::floor(time * 30.0 + 0.5 + 1e-6));
    const glm::vec4 white(0.9f, 0.9f, 0.92f, 1.0f), ink(0.01f, 0.015f, 0.04f, 0.65f);
    // Static: a translucent panel with a border and label blocks, bottom left.
    const int left = px(12), bottom = height - px(12), top = bottom - px(64);
    const int right = left + px(200);
    fill(ui, left, top, right, bottom, ink);
    fill(ui, left, top, right, top + px(2), white);
    fill(ui, left, bottom - px(2), right, bottom, white);
    fill(ui, left, top, left + px(2), bottom, white);
    fill(ui, right - px(2), top, right, bottom, white);
    for (int k = 0; k < 4; ++k)
        fill(ui, left + px(12 + 22 * k), top + px(10), left + px(28 + 22 * k), top + px(22), white);
    // Static: a crosshair at the centre.
    const int cx = width / 2, cy = height / 2;
    fill(ui, cx - px(10), cy - 1, cx + px(10), cy + 1, white);
    fill(ui, cx - 1, cy - px(10), cx + 1, cy + px(10), white);
    // Changing: a bar in the panel and a counter top right, every tick.
    const float filled = float(tick % 30) / 29.0f;
    fill(ui, left + px(12), top + px(34), left + px(12) + int(filled * float(px(176))),
         top + px(50), glm::vec4(0.95f, 0.45f, 0.05f, 1.0f));
    const int cell = px(14), gap = px(6), digits = 3;
    const int x0 = width - px(12) - digits * (cell + gap) - gap;
    fill(ui, x0 - gap, px(8), width - px(12), px(8) + 2 * cell + 2 * gap, ink);
    long value = tick;
    for (int d = digits - 1; d >= 0; --d, value /= 10)
        digit(ui, int(((value % 10) + 10) % 10), x0 + d * (cell + gap), px(8) + gap, cell,
              std::max(2, px(3)), white);
}

}  // namespace reprise::server
