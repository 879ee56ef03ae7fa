/* cmd_devices.c — deformctl devices: the daemon's HID devices (PROTOCOL.md 4.30..4.33).
 *
 *   deformctl devices                         one line per device: id, class, VID:PID, state,
 *                                             bound session, active session, name ("no HID
 *                                             devices" when there are none)
 *   deformctl devices bind DEVICE SESSION     DEVICE: its id (or its number n of id (1<<63)|n);
 *                                             SESSION: id or name, 0 or "none" to unbind */
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>

#include "client/deformctl/ctl.h"

static const char *class_name(unsigned c)
{
    static const char *const n[] = {"none", "knob", "3d-mouse", "pen"};
    return c < 4 ? n[c] : "?";
}

static const char *state_name(unsigned s)
{
    static const char *const n[] = {"?", "open", "closed", "error", "unplugged"};
    return s < 5 ? n[s] : "?";
}

static const char *backend_name(unsigned b)
{
    static const char *const n[] = {"?", "hidapi", "libusb", "replay"};
    return b < 4 ? n[b] : "?";
}

#define DEVICE_ID_BIT ((uint64_t)1 << 63)

/* DEVICE: a full id, or the device number n (id = (1 << 63) | n). DF_EINVAL when not a number. */
static int device_id(const char *arg, uint64_t *out, df_error *err)
{
    char *end = NULL;
    unsigned long long v = strtoull(arg, &end, 10);
    if (!arg[0] || *end || arg[0] == '-' || v == 0)
        return df_error_set(err, DF_EINVAL, "DEVICE '%s' is not a device id or number", arg);
    *out = v & DEVICE_ID_BIT ? v : v | DEVICE_ID_BIT;
    return DF_OK;
}

static void print_json(const df_msg_device_list *l)
{
    printf("{\"devices\":[");
    for (uint32_t i = 0; i < l->count; i++) {
        const df_msg_device_info *d = &l->items[i];
        printf("%s{\"device\":%" PRIu64 ",\"number\":%" PRIu64 ",\"class\":\"%s\",\"backend\":"
               "\"%s\",\"state\":\"%s\",\"bus\":%u,\"vid\":\"%04x\",\"pid\":\"%04x\","
               "\"bound_session\":%" PRIu64 ",\"active_session\":%" PRIu64 ",\"haptics\":%s,"
               "\"name\":", i ? "," : "", d->device_id, d->device_id & ~DEVICE_ID_BIT,
               class_name(d->dev_class), backend_name(d->backend), state_name(d->state), d->bus,
               d->vid, d->pid, d->bound_session, d->active_session,
               d->haptics ? "true" : "false");
        ctl_json_str(stdout, d->name);
        printf(",\"path\":");
        ctl_json_str(stdout, d->path);
        printf(",\"error\":");
        ctl_json_str(stdout, d->error);
        printf("}");
    }
    printf("]}\n");
}

static void print_text(const df_msg_device_list *l)
{
    if (l->count == 0) {
        printf("no HID devices\n");
        return;
    }
    printf("%-4s %-9s %-9s %-10s %-7s %-7s %s\n", "DEV", "CLASS", "VID:PID", "STATE", "BOUND",
           "ACTIVE", "NAME");
    for (uint32_t i = 0; i < l->count; i++) {
        const df_msg_device_info *d = &l->items[i];
        char bound[24], active[24], vp[16];
        snprintf(bound, sizeof bound, d->bound_session ? "%" PRIu64 : "-", d->bound_session);
        snprintf(active, sizeof active, d->active_session ? "%" PRIu64 : "-",
                 d->active_session);
        snprintf(vp, sizeof vp, "%04x:%04x", d->vid, d->pid);
        printf("%-4" PRIu64 " %-9s %-9s %-10s %-7s %-7s %s (%s%s%s)\n",
               d->device_id & ~DEVICE_ID_BIT, class_name(d->dev_class), vp, state_name(d->state),
               bound, active, d->name[0] ? d->name : "-", backend_name(d->backend),
               d->error[0] ? ": " : "", d->error);
    }
}

void ctl_device_state_print(const ctl_ctx *ctx, const df_msg_device_info *d)
{
    if (ctx->json) {
        printf("{\"kind\":\"device_state\",\"device\":%" PRIu64 ",\"class\":\"%s\","
               "\"state\":\"%s\",\"vid\":\"%04x\",\"pid\":\"%04x\",\"bound_session\":%" PRIu64
               ",\"active_session\":%" PRIu64 ",\"name\":", d->device_id,
               class_name(d->dev_class), state_name(d->state), d->vid, d->pid, d->bound_session,
               d->active_session);
        ctl_json_str(stdout, d->name);
        printf(",\"error\":");
        ctl_json_str(stdout, d->error);
        printf("}\n");
    } else {
        printf("device %" PRIu64 " %s %04x:%04x %s session %" PRIu64 " '%s'%s%s\n",
               d->device_id & ~DEVICE_ID_BIT, class_name(d->dev_class), d->vid, d->pid,
               state_name(d->state), d->active_session ? d->active_session : d->bound_session,
               d->name, d->error[0] ? ": " : "", d->error);
    }
    fflush(stdout);
}

static int run_devices(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    int bind = a->npos > 0 && strcmp(a->pos[0], "bind") == 0;
    if (a->npos > 0 && !bind) {
        char m[300];
        snprintf(m, sizeof m, "unknown devices subcommand '%s' (only 'bind')", a->pos[0]);
        return ctl_usage_error(ctx, cmd, m);
    }
    if (bind && a->npos != 3)
        return ctl_usage_error(ctx, cmd, "devices bind needs DEVICE and SESSION");
    df_error e;
    uint64_t did = 0, sid = 0;
    if (bind && device_id(a->pos[1], &did, &e) != DF_OK) return ctl_usage_error(ctx, cmd, e.msg);
    df_client *c = ctl_connect(ctx, cmd);
    if (!c) return CTL_EXIT_SERVER;
    int rc = DF_OK;
    if (bind) {
        if (strcmp(a->pos[2], "0") != 0 && strcmp(a->pos[2], "none") != 0)
            rc = ctl_session_id(c, a->pos[2], &sid, &e);
        if (rc == DF_OK) rc = df_client_device_bind(c, did, sid, &e);
        if (rc == DF_OK) {
            if (ctx->json)
                printf("{\"ok\":true,\"device\":%" PRIu64 ",\"session\":%" PRIu64 "}\n", did, sid);
            else if (sid)
                printf("device %" PRIu64 " bound to session %" PRIu64 "\n",
                       did & ~DEVICE_ID_BIT, sid);
            else
                printf("device %" PRIu64 " unbound: it follows the most recently active "
                       "session\n", did & ~DEVICE_ID_BIT);
        }
    } else {
        df_msg_device_list l;
        rc = df_client_devices_list(c, &l, &e);
        if (rc == DF_OK) {
            if (ctx->json) print_json(&l);
            else print_text(&l);
            df_msg_device_list_free(&l);
        }
    }
    if (rc != DF_OK) rc = ctl_fail(ctx, cmd, c, &e);
    df_client_close(c);
    return rc;
}

static const dc_cli_opt DEV_OPTS[] = {CTL_GLOBAL_OPTS};

const ctl_cmd ctl_cmds_devices[] = {
    {"devices", "devices [bind DEVICE SESSION]",
     "List the daemon's HID devices (class, VID:PID, state, bound and active session, name), "
     "or bind one to a session (SESSION 0 or none: follow the most recently active session).",
     DEV_OPTS, (int)(sizeof DEV_OPTS / sizeof DEV_OPTS[0]), -1, run_devices},
    {NULL, NULL, NULL, NULL, 0, 0, NULL}};
