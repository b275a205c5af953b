#pragma once
// A PNG read back with Cairo, for tests that check what a plot shows: its size and the pixels
// of a colour in a region. Shared by test_plot.cpp and test_run_plots.cpp.

#include <cairo.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>

namespace liedyn::test {

class Image {
 public:
  explicit Image(const std::filesystem::path& file)
      : surface_(cairo_image_surface_create_from_png(file.c_str()), cairo_surface_destroy) {}
  cairo_status_t status() const { return cairo_surface_status(surface_.get()); }
  int width() const { return cairo_image_surface_get_width(surface_.get()); }
  int height() const { return cairo_image_surface_get_height(surface_.get()); }
  // 0xAARRGGBB.
  std::uint32_t pixel(int x, int y) const {
    const unsigned char* row =
        cairo_image_surface_get_data(surface_.get()) +
        static_cast<std::ptrdiff_t>(y) * cairo_image_surface_get_stride(surface_.get());
    return reinterpret_cast<const std::uint32_t*>(row)[x];
  }
  // Pixels in [x0, x1) × [y0, y1) (fractions of the size) for which `test(r, g, b)` holds.
  int count(double x0, double x1, double y0, double y1,
            const std::function<bool(int, int, int)>& test) const {
    cairo_surface_flush(surface_.get());
    int n = 0;
    for (int y = static_cast<int>(y0 * height()); y < static_cast<int>(y1 * height()); ++y) {
      for (int x = static_cast<int>(x0 * width()); x < static_cast<int>(x1 * width()); ++x) {
        const std::uint32_t p = pixel(x, y);
        n += test((p >> 16) & 0xff, (p >> 8) & 0xff, p & 0xff) ? 1 : 0;
      }
    }
    return n;
  }

 private:
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface_;
};

}  // namespace liedyn::test
