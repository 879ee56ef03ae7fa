/* hid_mgr_internal.h — the HID manager's device registry, shared by hid_manager.c (discovery,
 * reader threads, listing, binding) and hid_mgr_drive.c (actions -> requests). Not a public
 * header: everything else uses hid_manager.h. Loop thread unless a field says otherwise. */
#ifndef DF_SERVER_HID_MGR_INTERNAL_H
#define DF_SERVER_HID_MGR_INTERNAL_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <uv.h>

#include "server/hid/hid_class.h"
#include "server/hid/hid_desc.h"
#include "server/hid/hid_manager.h"
#include "server/hid/hid_mapper.h"
#include "server/hid/hid_pen_target.h"
#include "server/hid/hid_source.h"

#define DF_HID_READ_TIMEOUT_MS 100  /* a reader thread checks its stop flag this often */
#define DF_HID_ID_BIT (1ull << 63)  /* device ids: DF_HID_ID_BIT | n, n = 1, 2, ... */

enum { DF_HID_BE_HIDAPI = 0, DF_HID_BE_LIBUSB = 1, DF_HID_BE_REPLAY = 2, DF_HID_BE_COUNT = 3 };

typedef struct df_hid_device df_hid_device;

/* A session's pen ray-cast cache (hid_pen_target.h), made on first use. */
typedef struct df_hid_pencache {
    uint64_t session_id;
    df_pen_cache *pc;
    struct df_hid_pencache *next;
} df_hid_pencache;

struct df_hid_device {
    struct df_hid_manager *mgr;
    uint64_t id;                 /* DF_HID_ID_BIT | n */
    int be;                      /* DF_HID_BE_* */
    df_hid_devinfo info;         /* owned copy (desc malloc'd) */
    int state;                   /* DF_DEVSTATE_*; CLOSED also before a replay device starts */
    char error[DF_MAX_ERROR_MSG_LEN + 1];
    df_hid_desc desc;            /* parsed descriptor (have_desc) */
    int have_desc;
    df_hid_class_info cls;
    df_hid_mapper map;
    int mapper_ok;               /* 0: class NONE or the mapper refused: reports are ignored */
    df_hid_dev *dev;             /* open handle, NULL when closed */
    pthread_t th;
    int th_running;              /* a reader thread exists (joined by close) */
    atomic_int stop;             /* set by the loop: the reader returns */
    /* Replay devices run in lock step with the loop: the reader posts one report and waits
     * until the loop has handled it (so output reports are captured at the replay time of the
     * report that caused them, and the end of the recording comes after its last report). */
    int lockstep;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int unacked;                 /* under mu: a posted report not handled yet */
    int present;                 /* seen by the last enumeration of its backend */
    /* driving */
    uint64_t bound;              /* DEVICE_BIND / DEVICE_VIEW session, 0 none */
    uint64_t active;             /* the session it drives now (0 none) */
    int have_view;
    double view_proj[16], viewport[4];
    int stroke;                  /* a stroke of this device is open on `stroke_session` */
    uint64_t stroke_session;
    double stroke_center[3];     /* pen: the hit the stroke began at */
    double stroke_strength;      /* last strength sent for the open stroke */
    int stroke_skipped;          /* the mapper's stroke had no hit / no view: ignore it */
    double cursor[3];            /* 3d-mouse cursor (mesh coordinates) of `cursor_session` */
    uint64_t cursor_session;
    int logged_no_view, logged_no_session, logged_error;
    /* stats */
    uint64_t events, strokes_begun, strokes_ended, actions, requests_failed;
    double last_tip[3], last_twist[3], last_strength, strength_max;
    df_hid_device *next;         /* registry, id order */
};

typedef struct df_hid_manager {
    df_server *srv;
    df_hid_backend *be[DF_HID_BE_COUNT];
    df_hid_device *devs;         /* id order */
    uint32_t ndev, next_n;
    uv_timer_t enum_timer;
    int timer_on;
    int replay_started;          /* replay devices were opened (first active session) */
    int stopping;
    atomic_int posted;           /* reports posted and not yet delivered */
    uint64_t events;             /* reports handled, all devices */
    df_hid_pencache *pens;
} df_hid_manager;

/* hid_mgr_drive.c ------------------------------------------------------------------------- */

/* Handles one input report of d (time_us: its event time) on the loop thread: picks the session,
 * feeds the mapper, applies its actions. */
void df_hid_drive_report(df_hid_device *d, const uint8_t *buf, size_t len, uint64_t time_us);

/* The device is going away (error, unplug): the mapper's unplug actions (its stroke ends through
 * BRUSH_END) are applied. */
void df_hid_drive_unplug(df_hid_device *d);

/* Ends d's open stroke (BRUSH_END on its behalf) if it has one; used when it is rebound. */
void df_hid_drive_end_stroke(df_hid_device *d);

/* The session d drives now (bound if alive, else the most recently active), or NULL. */
struct df_session *df_hid_drive_session(df_hid_device *d);

/* Frees the pen cache of session_id (all of them with 0). */
void df_hid_drive_pen_forget(df_hid_manager *m, uint64_t session_id);

/* hid_manager.c (hid_mgr_query.c: list, bind, view, stats) ------------------------------- */

/* The device with id `id`, or NULL. */
df_hid_device *df_hid_find(df_hid_manager *m, uint64_t id);

/* Fills the wire item of d. */
void df_hid_device_info(const df_hid_device *d, df_msg_device_info *out);

/* Sends DEVICE_STATE of d to the subscribers of session_id (0: the session d would drive now,
 * hid_mgr_drive.c's df_hid_drive_session; none: nothing is sent). */
void df_hid_device_announce(df_hid_device *d, uint64_t session_id);

#endif
