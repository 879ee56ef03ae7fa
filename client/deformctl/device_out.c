/* device_out.c — deformctl's text and JSON forms of the daemon's HID devices: the `devices`
 * listing and the DEVICE_STATE lines of `watch` (see ctl.h). Linkable without main.c (unit
 * tests). */
#include <inttypes.h>
#include <stdio.h>
#include <string.h>

#include "client/deformctl/ctl.h"

#define DEVICE_ID_BIT ((uint64_t)1 << 63)

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

static void print_text(const df_msg_device_list *l, int hid_on)
{
    if (l->count == 0) {
        printf(hid_on ? "no HID devices\n"
                      : "no HID devices: the daemon's HID subsystem is off (hid = off and no "
                        "hid_replay)\n");
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
        printf("{\"kind\":\"device_state\",\"device\":%" PRIu64 ",\"number\":%" PRIu64
               ",\"class\":\"%s\",\"state\":\"%s\",\"vid\":\"%04x\",\"pid\":\"%04x\","
               "\"bound_session\":%" PRIu64 ",\"active_session\":%" PRIu64 ",\"name\":",
               d->device_id, d->device_id & ~DEVICE_ID_BIT, class_name(d->dev_class),
               state_name(d->state), d->vid, d->pid, d->bound_session, d->active_session);
        ctl_json_str(stdout, d->name);
        printf(",\"error\":");
        ctl_json_str(stdout, d->error);
        printf("}\n");
    } else {
        uint64_t sid = d->active_session ? d->active_session : d->bound_session;
        char ses[24];
        snprintf(ses, sizeof ses, sid ? "%" PRIu64 : "-", sid);
        printf("device %" PRIu64 " %s %04x:%04x %s session %s '%s'%s%s\n",
               d->device_id & ~DEVICE_ID_BIT, class_name(d->dev_class), d->vid, d->pid,
               state_name(d->state), ses, d->name, d->error[0] ? ": " : "", d->error);
    }
    fflush(stdout);
}

void ctl_device_list_print(const ctl_ctx *ctx, const df_msg_device_list *l, int hid_on)
{
    if (ctx->json)
        print_json(l);
    else
        print_text(l, hid_on);
    fflush(stdout);
}
