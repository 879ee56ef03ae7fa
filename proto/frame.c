/* frame.c — frame header codec and framing helpers (see frame_codec.h, frame.h). */
#include "proto/frame_codec.h"

#include "proto/messages.h"

static int check_flags(uint16_t type, uint16_t flags, df_error *err)
{
    if (flags & ~DF_FLAGS_KNOWN)
        return df_error_set(err, DF_EPROTO_BADFLAGS, "frame flags 0x%04x: unknown bits 0x%04x",
                            flags, (unsigned)(flags & ~DF_FLAGS_KNOWN));
    if ((flags & DF_FLAG_REPLY) && (flags & DF_FLAG_EVENT))
        return df_error_set(err, DF_EPROTO_BADFLAGS, "frame flags 0x%04x: REPLY and EVENT together",
                            flags);
    if ((flags & DF_FLAG_ERROR) && !(flags & DF_FLAG_REPLY) && type != DF_MSG_ERROR)
        return df_error_set(err, DF_EPROTO_BADFLAGS,
                            "frame flags 0x%04x: ERROR without REPLY on type 0x%04x", flags, type);
    return DF_OK;
}

static int check_header(const df_frame_header *h, df_error *err)
{
    if (h->magic != DF_FRAME_MAGIC)
        return df_error_set(err, DF_EPROTO_BADMAGIC, "bad frame magic 0x%08x (want 0x%08x \"DFMD\")",
                            h->magic, DF_FRAME_MAGIC);
    if (h->payload_len > DF_MAX_FRAME_PAYLOAD)
        return df_error_set(err, DF_EPROTO_TOOLARGE, "frame payload %u bytes exceeds limit %u",
                            h->payload_len, DF_MAX_FRAME_PAYLOAD);
    if (h->version < DF_PROTO_VERSION_MIN || h->version > DF_PROTO_VERSION)
        return df_error_set(err, DF_EPROTO_BADVERSION,
                            "protocol version %u not supported (supported %u..%u)", h->version,
                            DF_PROTO_VERSION_MIN, DF_PROTO_VERSION);
    if (h->reserved != 0)
        return df_error_set(err, DF_EPROTO_RESERVED, "frame reserved field is 0x%04x, must be 0",
                            h->reserved);
    return check_flags(h->type, h->flags, err);
}

int df_frame_header_encode(const df_frame_header *h, uint8_t out[DF_FRAME_HEADER_SIZE],
                           df_error *err)
{
    int rc = check_header(h, err);
    if (rc)
        return rc;
    df_le32_store(out + 0, h->magic);
    df_le16_store(out + 4, h->version);
    df_le16_store(out + 6, h->type);
    df_le16_store(out + 8, h->flags);
    df_le16_store(out + 10, h->reserved);
    df_le64_store(out + 12, h->request_id);
    df_le32_store(out + 20, h->payload_len);
    return DF_OK;
}

int df_frame_header_decode(const uint8_t *p, size_t n, df_frame_header *h, df_error *err)
{
    if (n < DF_FRAME_HEADER_SIZE)
        return df_error_set(err, DF_EPROTO_TRUNCATED, "frame header truncated: %zu of %u bytes", n,
                            DF_FRAME_HEADER_SIZE);
    df_frame_header t;
    t.magic = df_le32_load(p + 0);
    t.version = df_le16_load(p + 4);
    t.type = df_le16_load(p + 6);
    t.flags = df_le16_load(p + 8);
    t.reserved = df_le16_load(p + 10);
    t.request_id = df_le64_load(p + 12);
    t.payload_len = df_le32_load(p + 20);
    int rc = check_header(&t, err);
    if (rc != DF_EPROTO_BADMAGIC)
        *h = t;
    return rc;
}

int df_frame_error_is_fatal(int code)
{
    return code == DF_EPROTO_BADMAGIC || code == DF_EPROTO_TOOLARGE ||
           code == DF_EPROTO_BADVERSION;
}

int df_frame_begin(df_buf *b, uint16_t type, uint16_t flags, uint64_t request_id, size_t *start,
                   df_error *err)
{
    if (type == 0)
        return df_error_set(err, DF_EPROTO_BADTYPE, "frame type 0 is not a message type");
    df_frame_header h = {DF_FRAME_MAGIC, DF_PROTO_VERSION, type, flags, 0, request_id, 0};
    uint8_t raw[DF_FRAME_HEADER_SIZE];
    int rc = df_frame_header_encode(&h, raw, err);
    if (rc)
        return rc;
    rc = df_buf_append(b, raw, sizeof raw, err);
    if (rc)
        return rc;
    *start = b->len - DF_FRAME_HEADER_SIZE;
    return DF_OK;
}

int df_frame_end(df_buf *b, size_t start, df_error *err)
{
    if (start > b->len || b->len - start < DF_FRAME_HEADER_SIZE ||
        df_le32_load(b->data + start) != DF_FRAME_MAGIC)
        return df_error_set(err, DF_EINVAL, "df_frame_end: no frame header at offset %zu", start);
    size_t payload = b->len - start - DF_FRAME_HEADER_SIZE;
    if (payload > DF_MAX_FRAME_PAYLOAD) {
        b->len = start;
        return df_error_set(err, DF_EPROTO_TOOLARGE, "frame payload %zu bytes exceeds limit %u",
                            payload, DF_MAX_FRAME_PAYLOAD);
    }
    df_le32_store(b->data + start + 20, (uint32_t)payload);
    return DF_OK;
}
