#pragma once
// A PNG read back with Cairo (from a file or from bytes in memory), for tests that check drawn
// pixels: render's joints at their pixel positions, the report's screenshot against a reference.
#include <cairo.h>

#include <cstdint>
#include <cstring>
#include <memory>
#include <string>

namespace orthomech::test {

struct PngImage {
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface{nullptr,
                                                                             cairo_surface_destroy};
  int width = 0, height = 0, stride = 0;  // width = 0: not read
  const unsigned char* data = nullptr;

  [[nodiscard]] static PngImage from_file(const std::string& path) {
    PngImage image;
    image.take(cairo_image_surface_create_from_png(path.c_str()));
    return image;
  }
  [[nodiscard]] static PngImage from_bytes(const std::string& bytes) {
    struct Reader {
      const std::string* bytes;
      size_t at = 0;
    } reader{&bytes};
    PngImage image;
    image.take(cairo_image_surface_create_from_png_stream(
        [](void* closure, unsigned char* out, unsigned int length) {
          auto* r = static_cast<Reader*>(closure);
          if (r->at + length > r->bytes->size()) return CAIRO_STATUS_READ_ERROR;
          std::memcpy(out, r->bytes->data() + r->at, length);
          r->at += length;
          return CAIRO_STATUS_SUCCESS;
        },
        &reader));
    return image;
  }
  // Cairo's ARGB32 pixel (i, j); the images are opaque, so premultiplied = plain colour.
  [[nodiscard]] uint32_t argb(int i, int j) const {
    uint32_t v = 0;
    std::memcpy(&v, data + static_cast<size_t>(j) * stride + static_cast<size_t>(i) * 4, 4);
    return v;
  }

 private:
  void take(cairo_surface_t* s) {
    surface.reset(s);
    if (cairo_surface_status(s) != CAIRO_STATUS_SUCCESS) return;
    cairo_surface_flush(s);
    width = cairo_image_surface_get_width(s);
    height = cairo_image_surface_get_height(s);
    stride = cairo_image_surface_get_stride(s);
    data = cairo_image_surface_get_data(s);
  }
};

}  // namespace orthomech::test
