/* record.c — the change log's recipe record layout (see record.h). */
#include "server/store/record.h"

#include <stdlib.h>
#include <string.h>

int df_record_encode(const df_recipe_record *r, uint8_t **out, size_t *len, df_error *err)
{
    if (!r || !r->recipe || !r->recipe_len || r->recipe_len > UINT32_MAX)
        return df_error_set(err, DF_EINVAL, "recipe record: no recipe, or one over 4 GiB");
    size_t n = DF_RECORD_HEADER + r->recipe_len;
    uint8_t *b = malloc(n);
    if (!b) return df_error_set(err, DF_ENOMEM, "recipe record: out of memory");
    uint32_t magic = DF_RECORD_MAGIC, rl = (uint32_t)r->recipe_len;
    memcpy(b, &magic, 4);
    memcpy(b + 4, &rl, 4);
    memcpy(b + 8, &r->base_version, 8);
    memcpy(b + 16, &r->checksum, 8);
    memcpy(b + 24, &r->replay_ns, 8);
    memcpy(b + DF_RECORD_HEADER, r->recipe, r->recipe_len);
    *out = b;
    *len = n;
    return DF_OK;
}

int df_record_decode(const uint8_t *b, size_t len, df_recipe_record *r, df_error *err)
{
    memset(r, 0, sizeof *r);
    uint32_t magic = 0, rl = 0;
    if (!b || len < DF_RECORD_HEADER)
        return df_error_set(err, DF_EFORMAT, "recipe record: %zu bytes, the header alone is %d",
                            len, DF_RECORD_HEADER);
    memcpy(&magic, b, 4);
    memcpy(&rl, b + 4, 4);
    if (magic != DF_RECORD_MAGIC)
        return df_error_set(err, DF_EFORMAT, "recipe record: magic 0x%08x, 0x%08x expected",
                            magic, DF_RECORD_MAGIC);
    if (rl == 0 || (size_t)rl != len - DF_RECORD_HEADER)
        return df_error_set(err, DF_EFORMAT, "recipe record: recipe of %u bytes in a %zu-byte "
                            "record (%zu expected)", rl, len, len - DF_RECORD_HEADER);
    memcpy(&r->base_version, b + 8, 8);
    memcpy(&r->checksum, b + 16, 8);
    memcpy(&r->replay_ns, b + 24, 8);
    r->recipe = b + DF_RECORD_HEADER;
    r->recipe_len = rl;
    return DF_OK;
}
