/* test_json_read.c -- json_read.h's readers on their own: each value type's checks (JSON type,
 * range with open and closed ends, integers, vectors' lengths and elements, strings' lengths,
 * enum names) and an object's member names (unknown, repeated, not an object), each fault's kind
 * and the path and words of its message; a cut name keeps whole UTF-8 characters. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "iir/json_read.h"

typedef struct sink {
    int faults;
    iir_json_fault fault;
    char path[IIR_JSON_PATH], msg[512];
} sink;

static void capture(void *ctx, iir_json_fault f, const char *path, const char *msg)
{
    sink *s = ctx;
    s->faults++;
    s->fault = f;
    snprintf(s->path, sizeof s->path, "%s", path);
    snprintf(s->msg, sizeof s->msg, "%s", msg);
}

/* Parses text, runs `expr` with v the parsed value and r a capturing reader. */
#define WITH(text, expr)                                                                           \
    do {                                                                                           \
        cJSON *v = cJSON_Parse(text);                                                              \
        assert_non_null(v);                                                                        \
        memset(&s, 0, sizeof s);                                                                   \
        expr;                                                                                      \
        cJSON_Delete(v);                                                                           \
    } while (0)

static void expect(const sink *s, iir_json_fault f, const char *path, const char *words)
{
    assert_int_equal(s->faults, 1);
    assert_int_equal(s->fault, f);
    assert_string_equal(s->path, path);
    if (!strstr(s->msg, words)) fail_msg("message \"%s\" lacks \"%s\"", s->msg, words);
}

static void test_numbers(void **state)
{
    (void)state;
    sink s;
    iir_json_reader r = {capture, &s};
    double x = 0;
    int64_t i = 0;
    iir_json_range closed = {0, 90, false, false, "degrees"}, open = {0, 90, true, false, NULL};
    WITH("45", assert_true(iir_json_number(&r, v, "a.b", closed, &x) && x == 45));
    assert_int_equal(s.faults, 0);
    WITH("0", assert_true(iir_json_number(&r, v, "a.b", closed, &x)));
    WITH("0", assert_false(iir_json_number(&r, v, "a.b", open, &x)));
    expect(&s, IIR_JSON_OUT_OF_RANGE, "a.b", "a.b must be in (0, 90], got 0");
    WITH("91", assert_false(iir_json_number(&r, v, "cone", closed, &x)));
    expect(&s, IIR_JSON_OUT_OF_RANGE, "cone", "must be in [0, 90] degrees, got 91");
    WITH("\"5\"", assert_false(iir_json_number(&r, v, "n", closed, &x)));
    expect(&s, IIR_JSON_BAD_TYPE, "n", "n must be a number, got a string");
    WITH("1e999", assert_false(iir_json_number(&r, v, "n", closed, &x)));
    expect(&s, IIR_JSON_OUT_OF_RANGE, "n", "must be a finite number");
    WITH("2.5", assert_false(iir_json_int(&r, v, "k", 0, 10, &i)));
    expect(&s, IIR_JSON_BAD_TYPE, "k", "k must be an integer, got 2.5");
    WITH("11", assert_false(iir_json_int(&r, v, "k", 0, 10, &i)));
    expect(&s, IIR_JSON_OUT_OF_RANGE, "k", "k must be in [0, 10], got 11");
    WITH("7", assert_true(iir_json_int(&r, v, "k", 0, 10, &i) && i == 7));
    bool b = false;
    WITH("1", assert_false(iir_json_bool(&r, v, "on", &b)));
    expect(&s, IIR_JSON_BAD_TYPE, "on", "on must be true or false, got a number");
    WITH("true", assert_true(iir_json_bool(&r, v, "on", &b) && b));
}

static void test_vectors(void **state)
{
    (void)state;
    sink s;
    iir_json_reader r = {capture, &s};
    iir_vec3 p = {0};
    WITH("[1, 2, 3]", assert_true(iir_json_vec3(&r, v, "p", -5, 5, &p)));
    assert_true(p.x == 1 && p.y == 2 && p.z == 3);
    WITH("[1, 2]", assert_false(iir_json_vec3(&r, v, "p", -5, 5, &p)));
    expect(&s, IIR_JSON_BAD_TYPE, "p", "p must be an array of 3 numbers, got 2 elements");
    WITH("{}", assert_false(iir_json_vec3(&r, v, "p", -5, 5, &p)));
    expect(&s, IIR_JSON_BAD_TYPE, "p", "got an object");
    WITH("[1, 9, 3]", assert_false(iir_json_vec3(&r, v, "lights[0].position", -5, 5, &p)));
    expect(&s, IIR_JSON_OUT_OF_RANGE, "lights[0].position[1]",
           "lights[0].position[1] must be in [-5, 5], got 9");
    WITH("[1, null, 3]", assert_false(iir_json_vec3(&r, v, "p", -5, 5, &p)));
    expect(&s, IIR_JSON_BAD_TYPE, "p[1]", "p[1] must be a number, got null");
    double wh[2];
    WITH("[2, 3]", assert_true(iir_json_numbers(&r, v, "size", 2, 0, 10, wh) && wh[1] == 3));
}

static void test_strings(void **state)
{
    (void)state;
    sink s;
    iir_json_reader r = {capture, &s};
    char out[8];
    WITH("\"abc\"", assert_true(iir_json_string(&r, v, "name", 1, 7, out)));
    assert_string_equal(out, "abc");
    WITH("\"\"", assert_false(iir_json_string(&r, v, "name", 1, 7, out)));
    expect(&s, IIR_JSON_OUT_OF_RANGE, "name", "name must not be empty");
    WITH("\"abcdefgh\"", assert_false(iir_json_string(&r, v, "name", 1, 7, out)));
    expect(&s, IIR_JSON_OUT_OF_RANGE, "name", "must be at most 7 bytes long, got 8");
    static const char *const kinds[] = {"spot", "point", NULL};
    int k = -1;
    WITH("\"point\"", assert_true(iir_json_enum(&r, v, "type", kinds, &k) && k == 1));
    WITH("\"sun\"", assert_false(iir_json_enum(&r, v, "type", kinds, &k)));
    expect(&s, IIR_JSON_OUT_OF_RANGE, "type",
           "type must be one of \"spot\", \"point\", got \"sun\"");
    /* a long name is cut to whole characters: 20 two-byte characters, cut at 39 bytes */
    char text[64] = "\"";
    for (int c = 0; c < 20; c++) strcat(text, "\xc3\xa9");
    strcat(text, "\"");
    WITH(text, assert_false(iir_json_enum(&r, v, "type", kinds, &k)));
    const char *got = strstr(s.msg, "got \"") + 5;
    assert_int_equal(strlen(got), 2 * 19 + 1); /* 19 whole characters and the closing quote */
}

static void test_fields(void **state)
{
    (void)state;
    sink s;
    iir_json_reader r = {capture, &s};
    static const char *const allowed[] = {"a", "b", NULL};
    WITH("{\"a\": 1, \"b\": 2}", assert_true(iir_json_fields(&r, v, "x", allowed)));
    assert_int_equal(s.faults, 0);
    WITH("{\"a\": 1, \"c\": 2}", assert_false(iir_json_fields(&r, v, "x", allowed)));
    expect(&s, IIR_JSON_UNKNOWN_FIELD, "x.c", "x.c: unknown field (known: a, b)");
    WITH("{\"a\": 1, \"a\": 2}", assert_false(iir_json_fields(&r, v, "", allowed)));
    expect(&s, IIR_JSON_UNKNOWN_FIELD, "a", "a: field given twice");
    WITH("[1]", assert_false(iir_json_fields(&r, v, "", allowed)));
    expect(&s, IIR_JSON_BAD_TYPE, "", "the top level must be an object, got an array");
    WITH("{\"a\": 1}", assert_null(iir_json_member(&r, v, "x", "b", false, NULL)));
    assert_int_equal(s.faults, 0);
    WITH("{\"a\": 1}", assert_null(iir_json_member(&r, v, "x", "b", true, " (a test)")));
    expect(&s, IIR_JSON_MISSING, "x.b", "x.b is required (a test)");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_numbers),
        cmocka_unit_test(test_vectors),
        cmocka_unit_test(test_strings),
        cmocka_unit_test(test_fields),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
