/* test_params.c -- parameter tables and sets (params.h) and the methods' use of them (method.h):
 * values against rows, text in and out, binding with a table's check, every method's tables
 * agreeing on shared names, and a live method keeping its VPLs through IIR_PARAM_LIVE changes. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#include "iir/incremental.h"
#include "iir/method.h"
#include "iir/params.h"
#include "iir/render.h"
#include "testutil.h"

typedef struct opts {
    int n;
    float f;
    bool b;
    int e;
    uint64_t u;
} opts;

static const char *const ABC[] = {"a", "b", "c", NULL};

static iir_status n_below_f(const void *o, const iir_params *given, const iir_param **bad,
                            iir_error *err);

static const iir_param ROWS[] = {
    {"n", IIR_PARAM_INT, offsetof(opts, n), 4, 1, 10, 8, NULL, "things", "n", IIR_PARAM_LIVE},
    {"f", IIR_PARAM_FLOAT, offsetof(opts, f), 0.5, 0, 100, 0, NULL, "", "f", IIR_PARAM_LIVE},
    {"b", IIR_PARAM_BOOL, offsetof(opts, b), 1, 0, 1, 0, NULL, "", "b", IIR_PARAM_RESTART},
    {"e", IIR_PARAM_ENUM, offsetof(opts, e), 2, 0, 2, 0, ABC, "", "e", IIR_PARAM_LIVE},
    {"u", IIR_PARAM_U64, offsetof(opts, u), 7, 0, 9007199254740992.0, 0, NULL, "", "u",
     IIR_PARAM_RESTART},
};
static const iir_param_table TABLE = {"test", ROWS, 5, n_below_f};

static iir_status n_below_f(const void *o, const iir_params *given, const iir_param **bad,
                            iir_error *err)
{
    (void)given;
    const opts *x = o;
    if ((float)x->n <= x->f) return IIR_OK;
    *bad = &ROWS[0];
    return iir_fail(err, IIR_ERR_INVALID, "n: n %d must not exceed f %g", x->n, (double)x->f);
}

static void test_values(void **state)
{
    (void)state;
    iir_error err = {0};
    double v = 0;
    assert_int_equal(iir_param_check(&ROWS[0], 10, false, &err), IIR_OK);
    assert_int_equal(iir_param_check(&ROWS[0], 11, false, &err), IIR_ERR_INVALID);
    assert_string_equal(err.msg, "n must be in [1, 10] things, got 11");
    assert_int_equal(iir_param_check(&ROWS[0], 9, true, &err), IIR_ERR_INVALID); /* live max 8 */
    assert_int_equal(iir_param_check(&ROWS[0], 2.5, false, &err), IIR_ERR_INVALID);
    assert_int_equal(iir_param_check(&ROWS[1], NAN, false, &err), IIR_ERR_INVALID);
    assert_int_equal(iir_param_check(&ROWS[1], 99.5, false, &err), IIR_OK);
    /* one default, for a live session and a command alike; only the maximum differs */
    assert_true(iir_param_max(&ROWS[0], true) == 8 && iir_param_max(&ROWS[0], false) == 10);

    assert_int_equal(iir_param_parse(&ROWS[3], "b", &v, &err), IIR_OK);
    assert_true(v == 1);
    assert_int_equal(iir_param_parse(&ROWS[3], "d", &v, &err), IIR_ERR_INVALID);
    assert_string_equal(err.msg, "e must be one of a, b, c, got 'd'");
    assert_int_equal(iir_param_parse(&ROWS[2], "off", &v, &err), IIR_OK);
    assert_true(v == 0);
    assert_int_equal(iir_param_parse(&ROWS[2], "maybe", &v, &err), IIR_ERR_INVALID);
    assert_int_equal(iir_param_parse(&ROWS[0], "7x", &v, &err), IIR_ERR_INVALID);
    assert_int_equal(iir_param_parse(&ROWS[4], "9007199254740992", &v, &err), IIR_OK);
    assert_true(v == 9007199254740992.0);

    /* format is what parse reads back */
    const double samples[] = {3, 0.1f, 1, 2, 123456789};
    for (int i = 0; i < 5; i++) {
        char text[64];
        double back = -1;
        iir_param_format(&ROWS[i], samples[i], text, sizeof text);
        assert_int_equal(iir_param_parse(&ROWS[i], text, &back, &err), IIR_OK);
        if (ROWS[i].type == IIR_PARAM_FLOAT)
            assert_true((float)back == (float)samples[i]);
        else
            assert_true(back == samples[i]);
    }
    char opt[32];
    iir_param_option_name(&ROWS[0], opt, sizeof opt);
    assert_string_equal(opt, "n");
    iir_param_check(&ROWS[0], 0, false, &err);
    iir_param_reword(&err, &ROWS[0], "--n");
    assert_string_equal(err.msg, "--n must be in [1, 10] things, got 0");
}

static void test_sets_and_binding(void **state)
{
    (void)state;
    iir_error err = {0};
    iir_params p = iir_params_default(), q = iir_params_default();
    opts o;
    const iir_param *bad = NULL;
    assert_int_equal(iir_params_bind(&TABLE, &p, NULL, &o, &bad, &err), IIR_ERR_INVALID);
    assert_ptr_equal(bad, &ROWS[0]); /* defaults n 4 > f 0.5: the table's check */
    assert_int_equal(iir_params_set(&p, &ROWS[1], 50, &err), IIR_OK);
    assert_int_equal(iir_params_set(&p, &ROWS[3], 0, &err), IIR_OK);
    assert_int_equal(iir_params_set(&p, &ROWS[0], 11, &err), IIR_ERR_INVALID);
    assert_int_equal(p.count, 2);
    assert_int_equal(iir_params_bind(&TABLE, &p, NULL, &o, &bad, &err), IIR_OK);
    assert_true(o.n == 4 && o.f == 50.f && o.b && o.e == 0 && o.u == 7);
    for (int i = 0; i < 5; i++)
        assert_true(iir_param_read(&ROWS[i], &o) == (i == 1 ? 50 : i == 3 ? 0 : ROWS[i].def));

    /* equality ignores order; merge replaces */
    assert_int_equal(iir_params_set(&q, &ROWS[3], 0, &err), IIR_OK);
    assert_int_equal(iir_params_set(&q, &ROWS[1], 50, &err), IIR_OK);
    assert_true(iir_params_equal(&p, &q));
    iir_params r = iir_params_default();
    assert_int_equal(iir_params_set(&r, &ROWS[1], 60, &err), IIR_OK);
    assert_true(iir_params_merge(&q, &r));
    assert_false(iir_params_equal(&p, &q));
    double v = 0;
    assert_true(iir_params_get(&q, "f", &v) && v == 60 && q.count == 2);
    assert_false(iir_params_has(&q, "n"));
}

/* Rows of one name mean one thing on the command line and in the protocol. */
static void test_methods_agree(void **state)
{
    (void)state;
    const iir_param_table *const *all = iir_method_all_tables();
    for (int a = 0; all[a]; a++)
        for (int i = 0; i < all[a]->count; i++) {
            const iir_param *x = &all[a]->rows[i], *y = iir_method_any_param(x->name);
            assert_non_null(y);
            assert_int_equal(x->type, y->type);
            assert_true(x->def >= x->lo && x->def <= x->hi);
            /* one default per parameter (issue 16), and one a live session may use */
            assert_true(x->def <= iir_param_max(x, true));
            assert_true(strlen(x->help) > 0);
            if (x->type == IIR_PARAM_ENUM) {
                for (int k = 0; x->choices[k] || y->choices[k]; k++)
                    assert_string_equal(x->choices[k], y->choices[k]);
                assert_true(x->hi == 0 || x->choices[(int)x->hi] != NULL);
            }
        }
    for (const char *const *n = iir_method_names(); *n; n++) {
        assert_non_null(iir_method_tables(*n));
        assert_true(strlen(iir_method_summary(*n)) > 0);
        iir_error err = {0};
        iir_params p = iir_params_default();
        assert_int_equal(iir_method_params_validate(*n, &p, NULL, NULL, &err), IIR_OK);
        assert_true(iir_method_memory(*n, &p, 64, 48) > 0);
    }
    /* the low-level defaults are the tables' */
    iir_incr_params ip = iir_incr_params_default();
    iir_params p = iir_params_default();
    assert_true(iir_method_param_value(iir_method_find_param("iir", "vpls"), &p) == ip.target);
    assert_true(iir_method_param_value(iir_method_find_param("iir", "kmin"), &p) == ip.k_min);
    assert_true(iir_method_param_value(iir_method_find_param("iir", "kmax"), &p) == ip.k_max);
    assert_true(iir_method_param_value(iir_method_find_param("iir", "weights"), &p) == ip.weights);
    assert_true((float)iir_method_param_value(iir_method_find_param("iir", "regen_threshold"),
                                              &p) == ip.regen_threshold);
    /* pt's frames have 1 sample everywhere; a converged frame (a still) has refine_passes */
    assert_true(iir_method_param_value(iir_method_find_param("pt", "spp"), &p) == 1);
    assert_int_equal(iir_method_converged_at("pt", &p),
                     (uint64_t)iir_method_param_value(iir_method_any_param("refine_passes"), &p));
    iir_indirect_params ind = iir_indirect_params_default();
    assert_true(iir_method_param_value(iir_method_any_param("interleave"), &p) == ind.interleave);
    assert_true((float)iir_method_param_value(iir_method_any_param("clamp"), &p) == ind.clamp);
    /* memory follows the parameters */
    iir_test_set(&p, "vpls", 1024);
    iir_params small = iir_params_default();
    assert_true(iir_method_memory("iir", &p, 64, 48) > iir_method_memory("iir", &small, 64, 48));
}

/* Live changes keep the VPL set (same ids); a restart parameter makes a new one. */
static void test_set_params_keeps_vpls(void **state)
{
    const iir_test_cornell *f = *state;
    iir_params p = iir_params_default();
    iir_test_set(&p, "vpls", 32);
    iir_test_set(&p, "sm_res", 16);
    iir_method *m = iir_test_method(f, "iir", &p);
    iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    iir_image *img = iir_image_create(16, 12);
    iir_frame_stats fs;
    iir_test_render(m, &v, img, &fs);
    uint32_t n = 0;
    const iir_vpl *vpls = iir_method_vpls(m, &n);
    uint32_t ids[64];
    for (uint32_t i = 0; i < n; i++) ids[i] = vpls[i].id;
    uint32_t before = n;

    iir_error err = {0};
    bool restarted = true;
    iir_test_set(&p, "kmax", 12);
    iir_test_set(&p, "clamp", 10);
    assert_int_equal(iir_method_set_params(m, &p, &restarted, &err), IIR_OK);
    assert_false(restarted);
    assert_true(iir_params_equal(iir_method_params(m), &p));
    vpls = iir_method_vpls(m, &n);
    assert_int_equal(n, before);
    for (uint32_t i = 0; i < n; i++) assert_int_equal(vpls[i].id, ids[i]);
    iir_test_render(m, &v, img, &fs);
    assert_int_equal(fs.vpl.regenerated, 0);

    iir_test_set(&p, "vpls", 48);
    assert_int_equal(iir_method_set_params(m, &p, &restarted, &err), IIR_OK);
    assert_true(restarted);
    iir_test_render(m, &v, img, &fs);
    assert_int_equal(fs.vpl.count, 48);

    /* refused parameters leave the method as it was */
    iir_test_set(&p, "kmin", 40);
    iir_test_set(&p, "kmax", 20);
    assert_int_equal(iir_method_set_params(m, &p, &restarted, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "kmin"));
    assert_false(iir_params_equal(iir_method_params(m), &p));
    iir_test_render(m, &v, img, &fs);
    assert_int_equal(fs.vpl.count, 48);
    iir_image_destroy(img);
    iir_method_destroy(m);
}

/* What params accept renders (issue 15, finding 6): iir refuses a view without lights up front, and
 * kmax 0 (no cap) is refused without insert_ms, the budget that then decides the insertions. */
static void test_accepted_renders(void **state)
{
    (void)state;
    iir_error err = {0};
    iir_light point = {.type = IIR_LIGHT_POINT, .name = "bulb", .intensity = {1, 1, 1}};
    iir_light spot = point;
    spot.type = IIR_LIGHT_SPOT;
    assert_int_equal(iir_method_supports("iir", &point, 1, &err), IIR_OK); /* its sphere */
    assert_int_equal(iir_method_supports("iir", &point, 0, &err), IIR_ERR_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "spot, point, sun or area light"));
    assert_int_equal(iir_method_supports("iir", (iir_light[]){point, spot}, 2, &err), IIR_OK);
    assert_int_equal(iir_method_supports("pt", &point, 1, &err), IIR_OK);
    assert_int_equal(iir_method_supports("nope", &point, 1, &err), IIR_ERR_INVALID);
    iir_params p = iir_params_default();
    assert_int_equal(iir_method_param_set(&p, "kmin", 0, &err), IIR_OK);
    assert_int_equal(iir_method_param_set(&p, "kmax", 0, &err), IIR_OK); /* in range... */
    const iir_param *bad = NULL;
    assert_int_equal(iir_method_params_validate("iir", &p, NULL, &bad, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "insert_ms")); /* ...but not without a budget */
    assert_int_equal(iir_method_param_set(&p, "insert_ms", 2, &err), IIR_OK);
    assert_int_equal(iir_method_params_validate("iir", &p, NULL, &bad, &err), IIR_OK);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_values),
        cmocka_unit_test(test_sets_and_binding),
        cmocka_unit_test(test_methods_agree),
        cmocka_unit_test(test_accepted_renders),
        cmocka_unit_test_setup_teardown(test_set_params_keeps_vpls, iir_test_cornell_setup,
                                        iir_test_cornell_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
