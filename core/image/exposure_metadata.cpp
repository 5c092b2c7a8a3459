// ReadExposureTime (image_io.h): the exposure a file records. JPEG through libexif; TIFF through
// libtiff's EXIF directory; EXR from its header's standard expTime attribute.
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <libexif/exif-data.h>
#include <tiffio.h>

#include <cmath>
#include <exception>
#include <memory>

#include "core/image/image_formats.h"
#include "core/image/image_io.h"
#include "core/util/error.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

std::optional<double> Positive(double seconds) {
  if (std::isfinite(seconds) && seconds > 0) return seconds;
  return std::nullopt;
}

std::optional<double> JpegExposureTime(const fs::path& path) {
  std::unique_ptr<ExifData, void (*)(ExifData*)> exif(exif_data_new_from_file(path.c_str()),
                                                       exif_data_unref);
  if (!exif) return std::nullopt;
  ExifEntry* entry = exif_data_get_entry(exif.get(), EXIF_TAG_EXPOSURE_TIME);
  if (entry == nullptr || entry->format != EXIF_FORMAT_RATIONAL || entry->components < 1)
    return std::nullopt;
  const ExifRational t = exif_get_rational(entry->data, exif_data_get_byte_order(exif.get()));
  if (t.denominator == 0) return std::nullopt;
  return Positive(static_cast<double>(t.numerator) / t.denominator);
}

std::optional<double> TiffExposureTime(const fs::path& path) {
  std::unique_ptr<TIFF, void (*)(TIFF*)> tif(TIFFOpen(path.c_str(), "r"), TIFFClose);
  if (!tif) Fail("{}: cannot read the image header", path.string());
  toff_t offset = 0;
  if (!TIFFGetField(tif.get(), TIFFTAG_EXIFIFD, &offset)) return std::nullopt;
  if (!TIFFReadEXIFDirectory(tif.get(), offset)) return std::nullopt;
  // libtiff hands an EXIF rational out as float or double, depending on its version.
  const TIFFField* field = TIFFFieldWithTag(tif.get(), EXIFTAG_EXPOSURETIME);
  if (field != nullptr && TIFFFieldSetGetSize(field) == 4) {
    float seconds = 0;
    if (!TIFFGetField(tif.get(), EXIFTAG_EXPOSURETIME, &seconds)) return std::nullopt;
    return Positive(seconds);
  }
  double seconds = 0;
  if (!TIFFGetField(tif.get(), EXIFTAG_EXPOSURETIME, &seconds)) return std::nullopt;
  return Positive(seconds);
}

std::optional<double> ExrExposureTime(const fs::path& path) {
  try {
    Imf::InputFile file(path.c_str());
    if (!Imf::hasExpTime(file.header())) return std::nullopt;
    return Positive(Imf::expTime(file.header()));
  } catch (const std::exception& e) {
    Fail("{}: cannot read the image header: {}", path.string(), e.what());
  }
}

}  // namespace

std::optional<double> ReadExposureTime(const fs::path& path) {
  ReadImageSpec(path);  // the same checks and errors as reading the image
  switch (image_formats::SniffFormat(path)) {
    case image_formats::FileFormat::kJpeg: return JpegExposureTime(path);
    case image_formats::FileFormat::kTiff: return TiffExposureTime(path);
    case image_formats::FileFormat::kExr: return ExrExposureTime(path);
    default: return std::nullopt;
  }
}

}  // namespace hdr4d
