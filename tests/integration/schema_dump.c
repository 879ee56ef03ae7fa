/* schema_dump.c — prints every number of proto/wire_schema.h and core/admm/admm_defaults.h as
 * tab-separated lines, for tests/integration/test_schema.py (which compiles and runs it):
 *   type NAME value lower_name request reply event
 *   enum PyClass kind C_PREFIX NAME value
 *   limit DF_NAME value
 *   const DF_NAME value            (frame and ring constants)
 *   magic DF_SHM_MAGIC text
 *   brush_default field value      admm_default field value      admm_nh_default field value
 * Header-only on purpose: it includes nothing else, so it proves the schema stands alone. */
#include <stdio.h>

#include "core/admm/admm_defaults.h"
#include "proto/wire_schema.h"

/* the enum constants the brush defaults name, built from the schema as messages.h does */
#define E_BRUSH(n, v) DF_BRUSH_##n = (v),
#define E_INTEG(n, v) DF_INTEG_##n = (v),
enum { DF_WIRE_BRUSH_TYPES(E_BRUSH) DF_WIRE_INTEGRATORS(E_INTEG) };

int main(void)
{
#define TYPE(n, v, name, req, rep, ev) \
    printf("type\t%s\t%u\t%s\t%s\t%s\t%s\n", #n, (unsigned)(v), #name, #req, #rep, #ev);
    DF_WIRE_MSG_TYPES(TYPE)
#define MEMBER(n, v) printf("enum\t%s\t%s\t%s\t%s\t%llu\n", cls, kind, prefix, #n, \
                            (unsigned long long)(v));
#define ENUM(list, pfx, py, k)                                                          \
    {                                                                                   \
        const char *cls = #py, *kind = #k, *prefix = #pfx;                              \
        list(MEMBER)                                                                    \
    }
    DF_WIRE_ENUMS(ENUM)
#define LIMIT(n) printf("limit\t%s\t%llu\n", #n, (unsigned long long)(n));
    DF_WIRE_LIMITS(LIMIT)
    printf("const\tDF_FRAME_MAGIC\t%llu\n", (unsigned long long)DF_FRAME_MAGIC);
    printf("const\tDF_PROTO_VERSION\t%llu\n", (unsigned long long)DF_PROTO_VERSION);
    printf("const\tDF_FRAME_HEADER_SIZE\t%llu\n", (unsigned long long)DF_FRAME_HEADER_SIZE);
    printf("const\tDF_SHM_HEADER_BYTES\t%llu\n", (unsigned long long)DF_SHM_HEADER_BYTES);
    printf("const\tDF_SHM_MIN_CAPACITY\t%llu\n", (unsigned long long)DF_SHM_MIN_CAPACITY);
    printf("const\tDF_SHM_MAX_CAPACITY\t%llu\n", (unsigned long long)DF_SHM_MAX_CAPACITY);
    printf("magic\tDF_SHM_MAGIC\t%s\n", DF_SHM_MAGIC);
    /* defaults: %.17g of the value as a double; enum-valued defaults print their number */
#define BRUSH_DEF(field, value) printf("brush_default\t%s\t%.17g\n", #field, (double)(value));
#define ADMM_DEF(field, value) printf("admm_default\t%s\t%.17g\n", #field, (double)(value));
#define NH_DEF(field, value) printf("admm_nh_default\t%s\t%.17g\n", #field, (double)(value));
    DF_WIRE_BRUSH_DEFAULTS(BRUSH_DEF)
    DF_ADMM_DEFAULTS(ADMM_DEF)
    DF_ADMM_DEFAULTS_NEOHOOKEAN(NH_DEF)
    return 0;
}
