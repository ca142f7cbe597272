// The UI layer drawn over the colour (premultiplied alpha).
#include "reprise/core/frame.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise {

void composite_ui(ImageView<const glm::vec4> color, ImageView<const glm::vec4> ui,
                  ImageView<glm::vec4> out) {
    REPRISE_ASSERT(out.width == color.width && out.height == color.height);
    REPRISE_ASSERT(ui.empty() || (ui.width == color.width && ui.height == color.height));
    parallel_for(
        0, color.height,
        [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const glm::vec4* c = color.row(y);
                glm::vec4* o = out.row(y);
                if (ui.empty()) {
                    if (o != c)
                        for (int x = 0; x < color.width; ++x) o[x] = c[x];
                    continue;
                }
                const glm::vec4* u = ui.row(y);
                for (int x = 0; x < color.width; ++x) o[x] = u[x] + (1.0f - u[x].a) * c[x];
            }
        },
        32);
}

}  // namespace reprise
