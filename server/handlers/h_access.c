/* h_access.c — SESSION_ACCESS and JOIN (PROTOCOL.md 4.34..4.36; handlers.h): a session's access
 * policy read or changed by its owner, and principals joining it with its join key.
 *
 * SESSION_ACCESS with mode, observers and flags all 0 reads the policy (observe right); any
 * other value changes it (own right: the owner or an admin). Switching to key mode without a
 * key, or flag NEW_KEY, makes a new random join key: the reply carries it (the only time it is
 * ever sent; the daemon keeps its SHA-256). JOIN with the right key makes the connection's
 * principal a member; a wrong key is EPERM ("wrong join key"), logged with the peer, and counts
 * against the peer's address in a token bucket like failed AUTHs (auth_fail_burst,
 * auth_fail_refill_s; net/auth_limit.h): a peer without tokens gets ELIMIT without its key
 * being checked. Counters: stats join_ok, join_failed, join_limited. A policy change is written to the store before it applies (journal.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <openssl/crypto.h>

#include "server/cluster/cluster.h"
#include "server/handlers/handlers.h"
#include "server/log.h"
#include "server/net/auth_limit.h"
#include "server/net/conn.h"
#include "server/session/access.h"
#include "server/session/membership.h"

static void info_fill(const df_session *s, df_msg_access_info *out)
{
    memset(out, 0, sizeof *out);
    out->session_id = s->id;
    out->mode = (uint8_t)s->acc.mode;
    out->observers = (uint8_t)s->acc.observers;
    out->members = (uint32_t)s->acc.n;
    snprintf(out->owner, sizeof out->owner, "%s", s->owner);
}

/* Makes `next` the policy of s: stored first (journal.h), then swapped in. */
static int apply(df_server *srv, df_session *s, df_membership *next, df_error *err)
{
    if (srv->store_ops && srv->store_ops->access &&
        srv->store_ops->access(srv, s, next, err) != DF_OK) {
        df_membership_free(next);
        return err ? err->code : DF_EIO;
    }
    df_membership_free(&s->acc);
    s->acc = *next;
    return DF_OK;
}

static df_session *find(df_req *r, uint64_t id, df_error *err)
{
    df_session *s = df_session_find(r->srv, id);
    if (!s && r->srv->cluster) df_cluster_route(r->srv, id, &s, err); /* cluster.h */
    else if (!s)
        df_error_set(err, DF_ENOTFOUND, "%s: no session %llu", df_msg_type_name(r->type),
                     (unsigned long long)id);
    return s;
}

int df_h_session_access(df_req *r, const uint8_t *p, df_error *err)
{
    df_msg_session_access m;
    int rc = df_msg_session_access_decode(p, r->len, &m, err);
    if (rc != DF_OK) return rc;
    df_session *s = find(r, m.session_id, err);
    if (!s) return err->code;
    int set = m.mode || m.observers || m.flags;
    if ((rc = df_access_require(r, s, set ? DF_RIGHT_OWN : DF_RIGHT_OBSERVE, err)) != DF_OK)
        return rc;
    df_msg_access_info out;
    if (set) {
        df_membership next;
        if ((rc = df_membership_copy(&next, &s->acc, err)) != DF_OK) return rc;
        if (m.mode) next.mode = m.mode;
        if (m.observers) next.observers = m.observers == 2;
        uint8_t key[DF_JOIN_KEY_BYTES];
        int new_key = (m.flags & DF_ACCESS_NEW_KEY) ||
                      (next.mode == DF_ACCESS_MODE_KEY && !next.has_key);
        if (new_key && (rc = df_membership_new_key(&next, key, err)) != DF_OK) {
            df_membership_free(&next);
            return rc;
        }
        if ((rc = apply(r->srv, s, &next, err)) != DF_OK) {
            OPENSSL_cleanse(key, sizeof key);
            return rc;
        }
        info_fill(s, &out);
        if (new_key) {
            out.has_key = 1;
            memcpy(out.key, key, sizeof key);
            OPENSSL_cleanse(key, sizeof key);
        }
        df_log(DF_LOG_INFO, "session %llu '%s': access %s, observers %s%s (by %s)",
               (unsigned long long)s->id, s->name, df_membership_mode_name(s->acc.mode),
               s->acc.observers ? "on" : "off", new_key ? ", new join key" : "",
               r->c->principal);
    } else {
        info_fill(s, &out);
    }
    df_req_reply_access_info(r, &out);
    OPENSSL_cleanse(&out, sizeof out);
    return DF_OK;
}

/* The rate-limit key of the requester: its TCP address, or its uid on the Unix socket. */
static const char *limit_host(const df_conn *c, char *buf, size_t cap)
{
    if (c->is_tcp) return c->peer_host;
    snprintf(buf, cap, "unix uid %u", c->peer_uid);
    return buf;
}

int df_h_join(df_req *r, const uint8_t *p, df_error *err)
{
    df_msg_join m;
    int rc = df_msg_join_decode(p, r->len, &m, err);
    if (rc != DF_OK) return rc;
    df_server *srv = r->srv;
    df_conn *c = r->c;
    if (!srv->join_limit) {
        if (!(srv->join_limit = calloc(1, sizeof *srv->join_limit))) {
            OPENSSL_cleanse(&m, sizeof m);
            return df_error_set(err, DF_ENOMEM, "join: out of memory");
        }
        df_auth_limit_init(srv->join_limit, srv->cfg.access.fail_burst,
                           srv->cfg.access.fail_refill_s);
    }
    char ubuf[48];
    const char *host = limit_host(c, ubuf, sizeof ubuf);
    uint64_t wait = df_auth_limit_wait(srv->join_limit, host, uv_now(srv->loop));
    if (wait) {
        srv->stats.join_limited++;
        OPENSSL_cleanse(&m, sizeof m);
        df_log(DF_LOG_WARN, "client %llu (%s, %s): join refused: too many wrong join keys",
               (unsigned long long)c->id, c->is_tcp ? c->peer_addr : host, c->principal);
        return df_error_set(err, DF_ELIMIT, "join: too many wrong join keys from %s; retry in "
                            "%llu s", host, (unsigned long long)((wait + 999) / 1000));
    }
    df_session *s = find(r, m.session_id, err);
    if (!s) {
        OPENSSL_cleanse(&m, sizeof m);
        return err->code;
    }
    int have = df_access_rights(c, s);
    df_msg_access_info out;
    if (s->acc.mode == DF_ACCESS_MODE_OPEN || (have & DF_RIGHT_OWN) ||
        df_membership_is_member(&s->acc, c->principal)) {
        OPENSSL_cleanse(&m, sizeof m); /* already a member: nothing to change */
        info_fill(s, &out);
        df_req_reply_access_info(r, &out);
        return DF_OK;
    }
    if (s->acc.mode == DF_ACCESS_MODE_OWNER) {
        OPENSSL_cleanse(&m, sizeof m);
        return df_error_set(err, DF_EPERM, "join: session '%s' is owner-only (owner %s): no one "
                            "joins it; its owner may switch it to key mode", s->name,
                            s->owner[0] ? s->owner : "none (admins)");
    }
    int ok = df_membership_key_ok(&s->acc, m.key, sizeof m.key);
    OPENSSL_cleanse(&m, sizeof m);
    if (!ok) {
        srv->stats.join_failed++;
        df_auth_limit_fail(srv->join_limit, host, uv_now(srv->loop));
        df_log(DF_LOG_WARN, "client %llu (%s, %s): join of session %llu '%s' failed: wrong join "
               "key", (unsigned long long)c->id, c->is_tcp ? c->peer_addr : host, c->principal,
               (unsigned long long)s->id, s->name);
        return df_error_set(err, DF_EPERM, "join: wrong join key for session '%s' (ask its "
                            "owner %s for the current key); nothing changed", s->name,
                            s->owner[0] ? s->owner : "(an admin)");
    }
    df_membership next;
    if ((rc = df_membership_copy(&next, &s->acc, err)) != DF_OK) return rc;
    if ((rc = df_membership_add(&next, c->principal, err)) != DF_OK) {
        df_membership_free(&next);
        return rc;
    }
    if ((rc = apply(srv, s, &next, err)) != DF_OK) return rc;
    srv->stats.join_ok++;
    df_log(DF_LOG_INFO, "session %llu '%s': %s joined (%d members)", (unsigned long long)s->id,
           s->name, c->principal, s->acc.n);
    info_fill(s, &out);
    df_req_reply_access_info(r, &out);
    return DF_OK;
}
