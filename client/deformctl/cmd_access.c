/* cmd_access.c — `deformctl access`, `deformctl join` and `deformctl peers`: a session's access
 * policy, joining a session with its join key (PROTOCOL.md 4.34..4.36) and who is connected to
 * it (4.38).
 *
 *   deformctl access SESSION [--mode open|key|owner] [--observers on|off] [--new-key]
 *       prints the policy ("session N: mode M, observers on|off, owner P, K members"); with
 *       options, changes it first (owner or admin). A new join key (--new-key, or a switch to
 *       key mode without one) is printed once as "join key HEX" (JSON: "key").
 *   deformctl join SESSION --key HEX
 *       becomes a member of SESSION (give its id: a session that admits no observers cannot be
 *       found by name) with the 64 hex digits of its join key.
 *   deformctl peers SESSION
 *       one line per connection subscribed to SESSION: "client ID 'NAME' as PRINCIPAL over
 *       unix|tcp[, edit][, shm][ (you)]" after "session N: K peers" (JSON: "peers" array). */
#include <inttypes.h>
#include <stdio.h>
#include <string.h>

#include <openssl/crypto.h>

#include "client/deformctl/ctl.h"

enum { O_MODE = CTL_NGLOBAL, O_OBSERVERS, O_NEW_KEY, O_ACCESS_COUNT };
enum { O_KEY = CTL_NGLOBAL, O_JOIN_COUNT };
enum { O_PEERS_COUNT = CTL_NGLOBAL };

static const dc_cli_opt ACCESS_OPTS[O_ACCESS_COUNT] = {
    CTL_GLOBAL_OPTS,
    {"mode", 1, "--mode open|key|owner   who may edit: everyone, members (join key), the owner"},
    {"observers", 1, "--observers on|off      whether non-members may observe (and list) it"},
    {"new-key", 0, "--new-key               make a new join key (printed once; old one stops)"},
};

static const dc_cli_opt JOIN_OPTS[O_JOIN_COUNT] = {
    CTL_GLOBAL_OPTS,
    {"key", 1, "--key HEX          the session's join key, 64 hex digits"},
};

static const dc_cli_opt PEERS_OPTS[O_PEERS_COUNT] = {CTL_GLOBAL_OPTS};

static const char *const MODES[] = {"open", "key", "owner", NULL};
static const char *const ON_OFF[] = {"off", "on", NULL};

static void print_info(const ctl_ctx *ctx, const df_msg_access_info *i)
{
    const char *mode = i->mode >= 1 && i->mode <= 3 ? MODES[i->mode - 1] : "?";
    char hex[2 * DF_JOIN_KEY_BYTES + 1] = "";
    for (unsigned k = 0; i->has_key && k < DF_JOIN_KEY_BYTES; k++)
        snprintf(hex + 2 * k, 3, "%02x", i->key[k]);
    if (ctx->json) {
        printf("{\"ok\":true,\"session\":%" PRIu64 ",\"mode\":\"%s\",\"observers\":%s,"
               "\"owner\":", i->session_id, mode, i->observers ? "true" : "false");
        ctl_json_str(stdout, i->owner);
        printf(",\"members\":%" PRIu32, i->members);
        if (i->has_key) printf(",\"key\":\"%s\"", hex);
        printf("}\n");
    } else {
        printf("session %" PRIu64 ": mode %s, observers %s, owner %s, %" PRIu32 " members\n",
               i->session_id, mode, i->observers ? "on" : "off",
               i->owner[0] ? i->owner : "none (admins)", i->members);
        if (i->has_key) printf("join key %s\n", hex);
    }
    OPENSSL_cleanse(hex, sizeof hex);
}

static int run_access(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    df_msg_session_access m;
    memset(&m, 0, sizeof m);
    df_error e;
    int k;
    if (a->val[O_MODE]) {
        if ((k = dc_cli_choice(a->val[O_MODE], "--mode", MODES, &e)) < 0)
            return ctl_usage_error(ctx, cmd, e.msg);
        m.mode = (uint8_t)(k + 1);
    }
    if (a->val[O_OBSERVERS]) {
        if ((k = dc_cli_choice(a->val[O_OBSERVERS], "--observers", ON_OFF, &e)) < 0)
            return ctl_usage_error(ctx, cmd, e.msg);
        m.observers = (uint8_t)(k + 1); /* 1 off, 2 on */
    }
    if (a->val[O_NEW_KEY]) m.flags |= DF_ACCESS_NEW_KEY;
    df_client *c = ctl_connect(ctx, cmd);
    if (!c) return CTL_EXIT_SERVER;
    df_msg_access_info info;
    int rc = ctl_session_id(c, a->pos[0], &m.session_id, &e);
    if (rc == DF_OK) rc = df_client_session_access(c, &m, &info, &e);
    if (rc != DF_OK) {
        rc = ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
        return rc;
    }
    print_info(ctx, &info);
    OPENSSL_cleanse(&info, sizeof info);
    df_client_close(c);
    return CTL_EXIT_OK;
}

/* 64 hex digits into key[DF_JOIN_KEY_BYTES]: 1, else 0. */
static int parse_hex_key(const char *s, uint8_t *key)
{
    if (strlen(s) != 2 * DF_JOIN_KEY_BYTES) return 0;
    for (unsigned i = 0; i < DF_JOIN_KEY_BYTES; i++) {
        unsigned v = 0;
        for (int j = 0; j < 2; j++) {
            char ch = s[2 * i + (unsigned)j];
            int d = ch >= '0' && ch <= '9' ? ch - '0' : ch >= 'a' && ch <= 'f' ? ch - 'a' + 10
                                                      : ch >= 'A' && ch <= 'F' ? ch - 'A' + 10
                                                                               : -1;
            if (d < 0) return 0;
            v = v * 16 + (unsigned)d;
        }
        key[i] = (uint8_t)v;
    }
    return 1;
}

static int run_join(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    uint8_t key[DF_JOIN_KEY_BYTES];
    if (!a->val[O_KEY]) return ctl_usage_error(ctx, cmd, "--key HEX is required");
    if (!parse_hex_key(a->val[O_KEY], key))
        return ctl_usage_error(ctx, cmd, "--key: give the join key as 64 hex digits");
    df_client *c = ctl_connect(ctx, cmd);
    if (!c) {
        OPENSSL_cleanse(key, sizeof key);
        return CTL_EXIT_SERVER;
    }
    df_error e;
    uint64_t sid = 0;
    df_msg_access_info info;
    int rc = ctl_session_id(c, a->pos[0], &sid, &e);
    if (rc == DF_OK) rc = df_client_join(c, sid, key, &info, &e);
    OPENSSL_cleanse(key, sizeof key);
    if (rc != DF_OK) {
        rc = ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
        return rc;
    }
    if (!ctx->json) printf("joined ");
    print_info(ctx, &info);
    df_client_close(c);
    return CTL_EXIT_OK;
}

static const char *transport_name(uint8_t t)
{
    return t == DF_TRANSPORT_UNIX ? "unix" : t == DF_TRANSPORT_TCP ? "tcp" : "?";
}

static void print_peers(const ctl_ctx *ctx, uint64_t sid, const df_msg_peer_list *l)
{
    if (ctx->json) {
        printf("{\"ok\":true,\"session\":%" PRIu64 ",\"peers\":[", sid);
        for (uint32_t i = 0; i < l->count; i++) {
            const df_msg_peer_info *p = &l->items[i];
            printf("%s{\"id\":%" PRIu64 ",\"name\":", i ? "," : "", p->client_id);
            ctl_json_str(stdout, p->name);
            printf(",\"principal\":");
            ctl_json_str(stdout, p->principal);
            printf(",\"transport\":\"%s\",\"self\":%s,\"edit\":%s,\"shm\":%s}",
                   transport_name(p->transport), p->flags & DF_PEER_SELF ? "true" : "false",
                   p->flags & DF_PEER_EDIT ? "true" : "false",
                   p->flags & DF_PEER_SHM ? "true" : "false");
        }
        printf("]}\n");
        return;
    }
    printf("session %" PRIu64 ": %" PRIu32 " peer%s\n", sid, l->count, l->count == 1 ? "" : "s");
    for (uint32_t i = 0; i < l->count; i++) {
        const df_msg_peer_info *p = &l->items[i];
        printf("client %" PRIu64 " '%s' as %s over %s%s%s%s\n", p->client_id, p->name,
               p->principal[0] ? p->principal : "-", transport_name(p->transport),
               p->flags & DF_PEER_EDIT ? ", edit" : "", p->flags & DF_PEER_SHM ? ", shm" : "",
               p->flags & DF_PEER_SELF ? " (you)" : "");
    }
}

static int run_peers(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    df_client *c = ctl_connect(ctx, cmd);
    if (!c) return CTL_EXIT_SERVER;
    df_error e;
    uint64_t sid = 0;
    df_msg_peer_list l = {0, NULL};
    int rc = ctl_session_id(c, a->pos[0], &sid, &e);
    if (rc == DF_OK) rc = df_client_session_peers(c, sid, &l, &e);
    if (rc != DF_OK) {
        rc = ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
        return rc;
    }
    print_peers(ctx, sid, &l);
    df_msg_peer_list_free(&l);
    df_client_close(c);
    return CTL_EXIT_OK;
}

const ctl_cmd ctl_cmds_access[] = {
    {"access", "access SESSION [--mode open|key|owner] [--observers on|off] [--new-key]",
     "Print the session's access policy (mode, observers, owner, members); with options, the "
     "owner (or an admin) changes it first. A new join key is printed once.",
     ACCESS_OPTS, O_ACCESS_COUNT, 1, run_access},
    {"join", "join SESSION --key HEX",
     "Become a member of a key-mode session with its join key (64 hex digits, from the "
     "owner's 'deformctl access SESSION --new-key'); members may edit. Give SESSION's id when "
     "the session admits no observers.",
     JOIN_OPTS, O_JOIN_COUNT, 1, run_join},
    {"peers", "peers SESSION",
     "List the connections subscribed to the session: id, HELLO name, principal, transport, "
     "whether each may edit or reads the shared-memory stream, and which one is you.",
     PEERS_OPTS, O_PEERS_COUNT, 1, run_peers},
    {NULL, NULL, NULL, NULL, 0, 0, NULL},
};
