/* dc_calls_access.c — libdeformclient calls of per-session access (PROTOCOL.md 4.34..4.36):
 * read or change a session's access policy (SESSION_ACCESS) and join a session (JOIN). */
#include <string.h>

#include <openssl/crypto.h>

#include "client/dc_client.h"

static int reply_info(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    return df_msg_access_info_decode(p, h->payload_len, user, err);
}

static int enc_access(const void *m, df_buf *out, df_error *err)
{
    return df_msg_session_access_encode(m, out, err);
}

static int enc_join(const void *m, df_buf *out, df_error *err)
{
    return df_msg_join_encode(m, out, err);
}

int df_client_session_access(df_client *c, const df_msg_session_access *m,
                             df_msg_access_info *out, df_error *err)
{
    df_msg_access_info t;
    memset(&t, 0, sizeof t);
    int rc = dc_request(c, DF_MSG_SESSION_ACCESS, enc_access, m, reply_info, &t, err);
    if (rc == DF_OK && t.session_id != m->session_id)
        rc = df_error_set(err, DF_EFORMAT, "session_access: the reply names session %llu, not "
                          "%llu", (unsigned long long)t.session_id,
                          (unsigned long long)m->session_id);
    if (rc == DF_OK && out) *out = t;
    OPENSSL_cleanse(&t, sizeof t);
    return rc;
}

int df_client_join(df_client *c, uint64_t session_id, const uint8_t *key,
                   df_msg_access_info *out, df_error *err)
{
    df_msg_join m;
    m.session_id = session_id;
    memcpy(m.key, key, sizeof m.key);
    df_msg_access_info t;
    memset(&t, 0, sizeof t);
    int rc = dc_request(c, DF_MSG_JOIN, enc_join, &m, reply_info, &t, err);
    OPENSSL_cleanse(&m, sizeof m);
    if (rc == DF_OK && out) *out = t;
    return rc;
}
