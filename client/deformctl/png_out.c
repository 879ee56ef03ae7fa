/* png_out.c — PNG output through libpng's simplified write API (see png_out.h). */
#include <errno.h>
#include <png.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "client/deformctl/png_out.h"

int ctl_png_write(const char *path, int w, int h, const uint8_t *rgb, df_error *err)
{
    if (!path || !path[0] || !rgb || w < 1 || h < 1)
        return df_error_set(err, DF_EINVAL, "png: nothing to write");
    char tmp[4200];
    int n = snprintf(tmp, sizeof tmp, "%s.tmp-%ld", path, (long)getpid());
    if (n < 0 || (size_t)n >= sizeof tmp)
        return df_error_set(err, DF_EINVAL, "png: path too long: %s", path);
    png_image im;
    memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    im.width = (png_uint_32)w;
    im.height = (png_uint_32)h;
    im.format = PNG_FORMAT_RGB;
    if (!png_image_write_to_file(&im, tmp, 0, rgb, (png_int_32)w * 3, NULL)) {
        int rc = df_error_set(err, DF_EIO, "cannot write %s: %s", path, im.message);
        png_image_free(&im);
        unlink(tmp);
        return rc;
    }
    if (rename(tmp, path) != 0) {
        int e = errno;
        unlink(tmp);
        return df_error_set(err, DF_EIO, "cannot write %s: %s", path, strerror(e));
    }
    return DF_OK;
}
