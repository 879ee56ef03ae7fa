/* png_out.h — writes an 8-bit RGB image as a PNG file with libpng (deformctl preview). */
#ifndef DF_DEFORMCTL_PNG_OUT_H
#define DF_DEFORMCTL_PNG_OUT_H

#include <stdint.h>

#include "core/common/df_error.h"

/* Writes the w x h image `rgb` (row-major, 3 bytes per pixel, no padding) to `path` as an 8-bit
 * RGB PNG (libpng's simplified API). The file is written to "PATH.tmp-PID" and renamed over
 * `path`, so a failure leaves no partial PNG at `path`. Errors: DF_EINVAL (size < 1 or NULL),
 * DF_EIO naming the path and libpng's or the system's reason. Single-threaded use. */
int ctl_png_write(const char *path, int w, int h, const uint8_t *rgb, df_error *err);

#endif
