/* test_wire_core_map.c — proto/wire_core_map.h: every wire enum value maps to the core value of
 * the same meaning, every value outside the wire enum (0, MAX + 1, 255) is refused without a
 * table read, energy maps both ways, and a BRUSH_BEGIN converts to the engine's brush. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "proto/wire_core_map.h"

static void test_brush_types(void **state)
{
    (void)state;
    static const struct { unsigned wire; df_kelvinlet_type core; } map[] = {
        {DF_BRUSH_GRAB, DF_KELVINLET_GRAB},   {DF_BRUSH_TWIST, DF_KELVINLET_TWIST},
        {DF_BRUSH_SCALE, DF_KELVINLET_SCALE}, {DF_BRUSH_PINCH, DF_KELVINLET_PINCH},
        {DF_BRUSH_AFFINE, DF_KELVINLET_AFFINE}};
    assert_int_equal(sizeof map / sizeof map[0], DF_BRUSH_TYPE_MAX);
    for (size_t i = 0; i < sizeof map / sizeof map[0]; i++) {
        df_kelvinlet_type t = (df_kelvinlet_type)-1;
        assert_int_equal(df_wire_brush_type_to_core(map[i].wire, &t), DF_OK);
        assert_int_equal(t, map[i].core);
    }
    static const unsigned bad[] = {0, DF_BRUSH_TYPE_MAX + 1, 255, 0xFFFFFFFFu};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        df_kelvinlet_type t = DF_KELVINLET_TWIST;
        assert_int_equal(df_wire_brush_type_to_core(bad[i], &t), DF_EINVAL);
        assert_int_equal(t, DF_KELVINLET_TWIST); /* untouched */
    }
}

static void test_integrators_and_pins(void **state)
{
    (void)state;
    df_kelvinlet_integrator g;
    assert_int_equal(df_wire_integrator_to_core(DF_INTEG_EULER, &g), DF_OK);
    assert_int_equal(g, DF_KELVINLET_EULER);
    assert_int_equal(df_wire_integrator_to_core(DF_INTEG_RK4, &g), DF_OK);
    assert_int_equal(g, DF_KELVINLET_RK4);
    assert_int_equal(df_wire_integrator_to_core(0, &g), DF_EINVAL);
    assert_int_equal(df_wire_integrator_to_core(3, &g), DF_EINVAL);
    int f = -1;
    assert_int_equal(df_wire_pin_flags_to_core(0, &f), DF_OK);
    assert_int_equal(f, 0);
    assert_int_equal(df_wire_pin_flags_to_core(DF_PIN_DISPLACEMENT | DF_PIN_GRADIENT, &f), DF_OK);
    assert_int_equal(f, DF_KELVINLET_PIN_DISPLACEMENT | DF_KELVINLET_PIN_GRADIENT);
    assert_int_equal(df_wire_pin_flags_to_core(DF_PIN_GRADIENT, &f), DF_OK);
    assert_int_equal(f, DF_KELVINLET_PIN_GRADIENT);
    assert_int_equal(df_wire_pin_flags_to_core(4, &f), DF_EINVAL);
}

static void test_energies_both_ways(void **state)
{
    (void)state;
    static const struct { unsigned wire; df_admm_energy core; } map[] = {
        {DF_ENERGY_ARAP, DF_ADMM_ARAP},   {DF_ENERGY_ACAP, DF_ADMM_ACAP},
        {DF_ENERGY_NEOHOOKEAN, DF_ADMM_NEOHOOKEAN}, {DF_ENERGY_CLOTH, DF_ADMM_CLOTH},
        {DF_ENERGY_POLYLINE, DF_ADMM_POLYLINE}};
    assert_int_equal(sizeof map / sizeof map[0], DF_ENERGY_MAX);
    for (size_t i = 0; i < sizeof map / sizeof map[0]; i++) {
        df_admm_energy e = DF_ADMM_ARAP; /* gcc -O1 (make tsan) cannot see the assert's exit */
        uint8_t w = 0;
        assert_int_equal(df_wire_energy_to_core(map[i].wire, &e), DF_OK);
        assert_int_equal(e, map[i].core);
        assert_int_equal(df_core_energy_to_wire(e, &w), DF_OK);
        assert_int_equal(w, map[i].wire);
    }
    df_admm_energy e;
    uint8_t w;
    assert_int_equal(df_wire_energy_to_core(0, &e), DF_EINVAL);
    assert_int_equal(df_wire_energy_to_core(DF_ENERGY_MAX + 1, &e), DF_EINVAL);
    assert_int_equal(df_core_energy_to_wire((df_admm_energy)99, &w), DF_EINVAL);
}

static void test_brush_begin_to_engine(void **state)
{
    (void)state;
    df_msg_brush m;
    df_msg_brush_defaults(&m);
    m.type = DF_BRUSH_PINCH;
    m.integrator = DF_INTEG_RK4;
    m.falloff = 3;
    m.steps = 9;
    m.moving = 1;
    m.radius = 0.25;
    m.center[2] = 4;
    df_kelvinlet_brush b;
    df_error e;
    assert_int_equal(df_wire_brush_to_core(&m, &b, &e), DF_OK);
    assert_int_equal(b.type, DF_KELVINLET_PINCH);
    assert_int_equal(b.integrator, DF_KELVINLET_RK4);
    assert_int_equal(b.order, 3);
    assert_int_equal(b.steps, 9);
    assert_int_equal(b.moving, 1);
    assert_true(b.radius == 0.25 && b.centre[2] == 4 && b.ratio == m.ratio && b.nu == m.nu);
    m.type = DF_BRUSH_TYPE_MAX + 1;
    assert_int_equal(df_wire_brush_to_core(&m, &b, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "type"));
    m.type = DF_BRUSH_GRAB;
    m.integrator = 7;
    assert_int_equal(df_wire_brush_to_core(&m, &b, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "integrator"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_brush_types),
        cmocka_unit_test(test_integrators_and_pins),
        cmocka_unit_test(test_energies_both_ways),
        cmocka_unit_test(test_brush_begin_to_engine),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
