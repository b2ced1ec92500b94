/* test_protocol.c -- the live protocol's messages (docs/protocol.md, server/protocol/protocol.h):
 * every error code parsing and applying can give, with the field's path; envelopes (size, JSON,
 * UTF-8, nesting, trailing text, duplicate keys); every params field at and past its bounds;
 * all-or-nothing application; light, camera and intensity rules; the recording's round trip
 * through iir_anim_parse; the frame header's bytes; the JSON replies read back; a seeded fuzz
 * loop over mutated messages. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <cjson/cJSON.h>

#include "iir/anim.h"
#include "iir/rng.h"
#include "protocol.h"
#include "protocol_internal.h"
#include "recording.h"
#include "testutil.h"

/* ======================== helpers ======================== */

static iird_limits LIM = {.max_width = 1920, .max_height = 1080};

static iird_msg parse_ok(const char *json)
{
    iird_msg m;
    iird_proto_error e;
    if (!iird_parse_message(json, strlen(json), &LIM, &m, &e))
        fail_msg("%s: unexpected %s at '%s': %s", json, iird_err_name(e.code), e.field, e.message);
    return m;
}

/* Parses json (len bytes) expecting code and field; returns the error. */
static iird_proto_error expect_n(const char *json, size_t len, iird_err code, const char *field)
{
    iird_msg m;
    iird_proto_error e;
    if (iird_parse_message(json, len, &LIM, &m, &e))
        fail_msg("%.200s: parsed, expected an error", json);
    if (e.code != code || strcmp(e.field, field) != 0)
        fail_msg("%.200s: got %s at '%s' (%s), expected %s at '%s'", json, iird_err_name(e.code),
                 e.field, e.message, iird_err_name(code), field);
    assert_true(strlen(e.message) > 0);
    assert_true(iird_utf8_valid(e.message, strlen(e.message)));
    return e;
}

static iird_proto_error expect(const char *json, iird_err code, const char *field)
{
    return expect_n(json, strlen(json), code, field);
}

static void assert_near3(iir_vec3 a, iir_vec3 b, float tol)
{
    if (iir_length(iir_sub(a, b)) > tol)
        fail_msg("(%.9g %.9g %.9g) != (%.9g %.9g %.9g)", a.x, a.y, a.z, b.x, b.y, b.z);
}

static iir_light spot(void)
{
    iir_light l = {.type = IIR_LIGHT_SPOT, .name = "spot"};
    l.position = iir_v3(0.f, 1.9f, 0.f);
    l.direction = iir_v3(0.f, -1.f, 0.f);
    l.up = iir_v3(0.f, 0.f, -1.f);
    l.cone_angle = iir_radians(60.f);
    l.smooth = iir_radians(5.f);
    l.intensity = iir_v3(4.f, 2.f, 1.f);
    return l;
}

static iir_camera cam(void)
{
    iir_camera c = {iir_v3(0.f, 1.f, 3.9f), iir_v3(0.f, 1.f, 0.f), iir_v3(0.f, 1.f, 0.f), 39.3f};
    return c;
}

/* Parses a reply and checks it is an object of the given type. */
static cJSON *reply_ok(char *text, const char *type)
{
    assert_non_null(text);
    cJSON *o = cJSON_Parse(text);
    if (!o) fail_msg("reply is not JSON: %s", text);
    free(text);
    assert_true(cJSON_IsObject(o));
    assert_string_equal(cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(o, "type")), type);
    return o;
}

static double num(const cJSON *o, const char *name)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, name);
    if (!cJSON_IsNumber(v)) fail_msg("member %s is not a number", name);
    return v->valuedouble;
}

static iir_vec3 vec(const cJSON *o, const char *name)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, name);
    assert_true(cJSON_IsArray(v) && cJSON_GetArraySize(v) == 3);
    return iir_v3((float)cJSON_GetArrayItem(v, 0)->valuedouble,
                  (float)cJSON_GetArrayItem(v, 1)->valuedouble,
                  (float)cJSON_GetArrayItem(v, 2)->valuedouble);
}

/* ======================== envelopes ======================== */

static void test_envelope(void **state)
{
    (void)state;
    expect_n("", 0, IIRD_E_BAD_JSON, "");
    expect_n(NULL, 0, IIRD_E_BAD_JSON, "");
    expect("   ", IIRD_E_BAD_JSON, "");
    expect("[]", IIRD_E_BAD_JSON, "");
    expect("\"hello\"", IIRD_E_BAD_JSON, "");
    expect("5", IIRD_E_BAD_JSON, "");
    expect("null", IIRD_E_BAD_JSON, "");
    expect("{", IIRD_E_BAD_JSON, "");
    expect("{\"type\":\"hello\",}", IIRD_E_BAD_JSON, "");
    expect("{\"type\":\"hello\"} x", IIRD_E_BAD_JSON, "");
    expect("{\"type\":\"hello\"}{}", IIRD_E_BAD_JSON, "");
    expect("{\"type\":\"hello\"}]", IIRD_E_BAD_JSON, "");
    parse_ok(" {\"type\":\"hello\"} \r\n\t");
    /* a NUL byte inside the buffer, and bytes that are not UTF-8 */
    expect_n("{\"type\":\"hello\"}\0", 17, IIRD_E_BAD_JSON, "");
    expect_n("{\"type\":\"he\0lo\"}", 16, IIRD_E_BAD_JSON, "");
    expect("{\"type\":\"hello\",\"client\":\"\xff\"}", IIRD_E_BAD_JSON, "");
    expect("{\"type\":\"hello\",\"client\":\"\xc0\xaf\"}", IIRD_E_BAD_JSON, "");     /* overlong */
    expect("{\"type\":\"hello\",\"client\":\"\xed\xa0\x80\"}", IIRD_E_BAD_JSON, ""); /* surrogate */
    expect("{\"type\":\"hello\",\"client\":\"\\ud800\"}", IIRD_E_BAD_JSON, ""); /* lone \u escape */
    parse_ok("{\"type\":\"hello\",\"client\":\"caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80\"}");
    /* only len bytes are read: what follows in memory does not matter */
    const char *buf = "{\"type\":\"hello\"}garbage";
    iird_msg m;
    iird_proto_error e;
    assert_true(iird_parse_message(buf, 16, &LIM, &m, &e));
    assert_int_equal(m.type, IIRD_MSG_HELLO);
}

static void test_size_and_nesting(void **state)
{
    (void)state;
    size_t n = IIRD_MAX_MESSAGE_BYTES + 1;
    char *big = malloc(n + 1);
    assert_non_null(big);
    /* exactly the limit (padded with spaces) is fine; one byte more is too large */
    memset(big, ' ', n);
    memcpy(big, "{\"type\":\"hello\"}", 16);
    big[n] = '\0';
    iird_msg m;
    iird_proto_error e;
    assert_true(iird_parse_message(big, IIRD_MAX_MESSAGE_BYTES, &LIM, &m, &e));
    e = expect_n(big, n, IIRD_E_TOO_LARGE, "");
    assert_int_equal(e.seq, IIRD_NO_SEQ);
    /* nesting: past cJSON's limit it is bad JSON (not a crash); within it a field of bad type */
    for (size_t i = 0; i < n; i++) big[i] = '[';
    expect_n(big, IIRD_MAX_MESSAGE_BYTES, IIRD_E_BAD_JSON, "");
    size_t at = (size_t)sprintf(big, "{\"type\":\"light\",\"position\":");
    for (int i = 0; i < 2000; i++) big[at++] = '[';
    for (int i = 0; i < 2000; i++) big[at++] = ']';
    big[at++] = '}';
    expect_n(big, at, IIRD_E_BAD_JSON, "");
    at = (size_t)sprintf(big, "{\"type\":\"light\",\"position\":");
    for (int i = 0; i < 500; i++) big[at++] = '[';
    for (int i = 0; i < 500; i++) big[at++] = ']';
    big[at++] = '}';
    expect_n(big, at, IIRD_E_BAD_TYPE, "light.position");
    at = (size_t)sprintf(big, "{\"type\":\"light\",\"position\":");
    for (int i = 0; i < 500; i++) at += (size_t)sprintf(big + at, "{\"a\":");
    big[at++] = '0';
    for (int i = 0; i < 500; i++) big[at++] = '}';
    big[at++] = '}';
    expect_n(big, at, IIRD_E_BAD_TYPE, "light.position");
    /* many members: every one is looked at (duplicates of a known field, then an unknown one) */
    at = (size_t)sprintf(big, "{\"type\":\"params\"");
    while (at < 60000) at += (size_t)sprintf(big + at, ",\"x%zu\":0", at);
    big[at++] = '}';
    expect_n(big, at, IIRD_E_UNKNOWN_FIELD, "params.x16");
    free(big);
}

static void test_type_and_seq(void **state)
{
    (void)state;
    iird_proto_error e = expect("{\"seq\":1}", IIRD_E_BAD_TYPE, "type");
    assert_int_equal(e.seq, 1);
    expect("{\"type\":5}", IIRD_E_BAD_TYPE, "type");
    expect("{\"type\":null}", IIRD_E_BAD_TYPE, "type");
    e = expect("{\"type\":\"Light\",\"seq\":7}", IIRD_E_UNKNOWN_TYPE, "type");
    assert_int_equal(e.seq, 7);
    assert_non_null(strstr(e.message, "light"));
    expect("{\"type\":\"welcome\"}", IIRD_E_UNKNOWN_TYPE, "type");
    expect("{\"type\":\"hello\",\"seq\":-1}", IIRD_E_OUT_OF_RANGE, "seq");
    e = expect("{\"type\":\"hello\",\"seq\":4294967295}", IIRD_E_OUT_OF_RANGE, "seq");
    assert_int_equal(e.seq, IIRD_NO_SEQ);
    expect("{\"type\":\"hello\",\"seq\":1.5}", IIRD_E_BAD_TYPE, "seq");
    expect("{\"type\":\"hello\",\"seq\":\"1\"}", IIRD_E_BAD_TYPE, "seq");
    expect("{\"type\":\"hello\",\"seq\":1e400}", IIRD_E_OUT_OF_RANGE, "seq");
    expect("{\"type\":\"hello\",\"seq\":-1e400}", IIRD_E_OUT_OF_RANGE, "seq");
    /* seq is checked before the type */
    expect("{\"type\":\"nope\",\"seq\":true}", IIRD_E_BAD_TYPE, "seq");
    iird_msg m = parse_ok("{\"type\":\"hello\",\"seq\":4294967294}");
    assert_int_equal(m.seq, 4294967294LL);
    m = parse_ok("{\"seq\":0,\"type\":\"hello\"}");
    assert_int_equal(m.seq, 0);
    m = parse_ok("{\"type\":\"hello\"}");
    assert_int_equal(m.seq, IIRD_NO_SEQ);
    /* later errors echo a valid seq */
    e = expect("{\"type\":\"light\",\"seq\":3,\"cone_angle\":120}", IIRD_E_OUT_OF_RANGE,
               "light.cone_angle");
    assert_int_equal(e.seq, 3);
    assert_non_null(strstr(e.message, "120"));
}

static void test_unknown_and_duplicate(void **state)
{
    (void)state;
    iird_proto_error e =
        expect("{\"type\":\"light\",\"positon\":[0,1,0]}", IIRD_E_UNKNOWN_FIELD, "light.positon");
    assert_non_null(strstr(e.message, "position"));
    expect("{\"type\":\"camera\",\"fov_y\":40}", IIRD_E_UNKNOWN_FIELD, "camera.fov_y");
    expect("{\"type\":\"params\",\"Vpls\":4}", IIRD_E_UNKNOWN_FIELD, "params.Vpls");
    expect("{\"type\":\"hello\",\"\":1}", IIRD_E_UNKNOWN_FIELD, "hello.");
    expect("{\"type\":\"light\",\"cone_angle\":30,\"cone_angle\":40}", IIRD_E_BAD_JSON,
           "light.cone_angle");
    expect("{\"type\":\"light\",\"type\":\"camera\",\"fov\":40}", IIRD_E_BAD_JSON, "type");
    e = expect("{\"type\":\"hello\",\"seq\":1,\"seq\":2}", IIRD_E_BAD_JSON, "seq");
    assert_int_equal(e.seq, 1);
    /* a long unknown name is cut to the field buffer at a character boundary */
    char json[600], name[400] = "";
    for (int i = 0; i < 100; i++) strcat(name, "\xc3\xa9"); /* é, 2 bytes */
    snprintf(json, sizeof json, "{\"type\":\"light\",\"%s\":1}", name);
    iird_msg m;
    assert_false(iird_parse_message(json, strlen(json), &LIM, &m, &e));
    assert_int_equal(e.code, IIRD_E_UNKNOWN_FIELD);
    assert_true(strlen(e.field) < sizeof e.field && strlen(e.field) > 10);
    assert_true(iird_utf8_valid(e.field, strlen(e.field)));
    assert_true(iird_utf8_valid(e.message, strlen(e.message)));
}

/* ======================== hello, scene, pick, snapshot, record ======================== */

static void test_hello(void **state)
{
    (void)state;
    iird_msg m =
        parse_ok("{\"type\":\"hello\",\"protocol\":1,\"token\":\"s3cret\",\"client\":\"x\"}");
    assert_int_equal(m.type, IIRD_MSG_HELLO);
    assert_int_equal(m.u.hello.protocol, 1);
    assert_true(m.u.hello.has_token);
    assert_string_equal(m.u.hello.token, "s3cret");
    assert_string_equal(m.u.hello.client, "x");
    m = parse_ok("{\"type\":\"hello\"}");
    assert_false(m.u.hello.has_token);
    assert_int_equal(m.u.hello.protocol, 1);
    expect("{\"type\":\"hello\",\"protocol\":2}", IIRD_E_UNSUPPORTED, "hello.protocol");
    expect("{\"type\":\"hello\",\"protocol\":1e300}", IIRD_E_UNSUPPORTED, "hello.protocol");
    expect("{\"type\":\"hello\",\"protocol\":1.5}", IIRD_E_BAD_TYPE, "hello.protocol");
    expect("{\"type\":\"hello\",\"protocol\":\"1\"}", IIRD_E_BAD_TYPE, "hello.protocol");
    expect("{\"type\":\"hello\",\"protocol\":1e400}", IIRD_E_OUT_OF_RANGE, "hello.protocol");
    expect("{\"type\":\"hello\",\"token\":5}", IIRD_E_BAD_TYPE, "hello.token");
    expect("{\"type\":\"hello\",\"client\":[]}", IIRD_E_BAD_TYPE, "hello.client");
    char json[700], s[300];
    memset(s, 'a', 256);
    s[256] = '\0';
    snprintf(json, sizeof json, "{\"type\":\"hello\",\"token\":\"%s\"}", s);
    m = parse_ok(json);
    assert_int_equal(strlen(m.u.hello.token), 256);
    snprintf(json, sizeof json, "{\"type\":\"hello\",\"token\":\"%sa\"}", s);
    expect(json, IIRD_E_OUT_OF_RANGE, "hello.token");
    s[129] = '\0';
    snprintf(json, sizeof json, "{\"type\":\"hello\",\"client\":\"%s\"}", s);
    expect(json, IIRD_E_OUT_OF_RANGE, "hello.client");
}

static void test_scene_pick_snapshot_record(void **state)
{
    (void)state;
    iird_msg m = parse_ok("{\"type\":\"scene\",\"name\":\"cornell_box\"}");
    assert_int_equal(m.type, IIRD_MSG_SCENE);
    assert_string_equal(m.u.scene.name, "cornell_box");
    expect("{\"type\":\"scene\"}", IIRD_E_BAD_TYPE, "scene.name");
    expect("{\"type\":\"scene\",\"name\":3}", IIRD_E_BAD_TYPE, "scene.name");
    const char *bad[] = {"../etc", "a/b", "a\\\\b", "", ".hidden", "a..b", "x\\ny"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char json[100];
        snprintf(json, sizeof json, "{\"type\":\"scene\",\"name\":\"%s\"}", bad[i]);
        expect(json, IIRD_E_BAD_FIELD, "scene.name");
    }
    char json[400], s[200];
    memset(s, 'a', 129);
    s[129] = '\0';
    snprintf(json, sizeof json, "{\"type\":\"scene\",\"name\":\"%s\"}", s);
    expect(json, IIRD_E_OUT_OF_RANGE, "scene.name");

    m = parse_ok("{\"type\":\"pick\",\"x\":10.5,\"y\":0}");
    assert_true(m.u.pick.x == 10.5 && m.u.pick.y == 0.0);
    expect("{\"type\":\"pick\",\"x\":10}", IIRD_E_BAD_TYPE, "pick.y");
    expect("{\"type\":\"pick\",\"x\":-1,\"y\":0}", IIRD_E_OUT_OF_RANGE, "pick.x");
    expect("{\"type\":\"pick\",\"x\":0,\"y\":1080}", IIRD_E_OUT_OF_RANGE, "pick.y");
    expect("{\"type\":\"pick\",\"x\":1e400,\"y\":0}", IIRD_E_OUT_OF_RANGE, "pick.x");
    expect("{\"type\":\"pick\",\"x\":\"1\",\"y\":0}", IIRD_E_BAD_TYPE, "pick.x");
    iird_proto_error e;
    m = parse_ok("{\"type\":\"pick\",\"seq\":9,\"x\":600,\"y\":10}");
    assert_false(iird_check_pick(&m, 512, 384, &e));
    assert_int_equal(e.code, IIRD_E_OUT_OF_RANGE);
    assert_string_equal(e.field, "pick.x");
    assert_int_equal(e.seq, 9);
    m = parse_ok("{\"type\":\"pick\",\"x\":511.9,\"y\":384}");
    assert_false(iird_check_pick(&m, 512, 384, &e));
    assert_string_equal(e.field, "pick.y");
    m = parse_ok("{\"type\":\"pick\",\"x\":511.9,\"y\":383.9}");
    assert_true(iird_check_pick(&m, 512, 384, &e));

    m = parse_ok("{\"type\":\"snapshot\",\"format\":\"exr\"}");
    assert_true(m.u.snapshot.exr);
    m = parse_ok("{\"type\":\"snapshot\",\"format\":\"png\"}");
    assert_false(m.u.snapshot.exr);
    e = expect("{\"type\":\"snapshot\",\"format\":\"jpg\"}", IIRD_E_OUT_OF_RANGE,
               "snapshot.format");
    assert_non_null(strstr(e.message, "\"png\", \"exr\""));
    expect("{\"type\":\"snapshot\"}", IIRD_E_BAD_TYPE, "snapshot.format");
    expect("{\"type\":\"snapshot\",\"format\":1}", IIRD_E_BAD_TYPE, "snapshot.format");

    m = parse_ok("{\"type\":\"record\",\"action\":\"start\"}");
    assert_true(m.u.record.start);
    assert_int_equal(m.u.record.fps, 30);
    m = parse_ok("{\"type\":\"record\",\"action\":\"start\",\"fps\":240}");
    assert_int_equal(m.u.record.fps, 240);
    m = parse_ok("{\"type\":\"record\",\"action\":\"stop\"}");
    assert_false(m.u.record.start);
    expect("{\"type\":\"record\",\"action\":\"start\",\"fps\":0}", IIRD_E_OUT_OF_RANGE,
           "record.fps");
    expect("{\"type\":\"record\",\"action\":\"start\",\"fps\":241}", IIRD_E_OUT_OF_RANGE,
           "record.fps");
    expect("{\"type\":\"record\",\"action\":\"start\",\"fps\":2.5}", IIRD_E_BAD_TYPE, "record.fps");
    expect("{\"type\":\"record\",\"action\":\"stop\",\"fps\":30}", IIRD_E_BAD_FIELD, "record.fps");
    expect("{\"type\":\"record\",\"action\":\"pause\"}", IIRD_E_OUT_OF_RANGE, "record.action");
    expect("{\"type\":\"record\"}", IIRD_E_BAD_TYPE, "record.action");
}

/* ======================== light and camera ======================== */

static void test_light_parse(void **state)
{
    (void)state;
    iird_msg m = parse_ok("{\"type\":\"light\",\"position\":[0,1e6,-1e6],\"direction\":[0,0,-2],"
                          "\"cone_angle\":90,\"intensity\":[1,2,1e6]}");
    assert_int_equal(m.type, IIRD_MSG_LIGHT);
    assert_int_equal(m.u.light.has, (1u << IIRD_L_POSITION) | (1u << IIRD_L_DIRECTION) |
                                        (1u << IIRD_L_CONE) | (1u << IIRD_L_INTENSITY));
    assert_near3(m.u.light.direction, iir_v3(0, 0, -1), 0.f);
    assert_true(m.u.light.cone_angle_deg == 90.f);
    assert_false(m.u.light.intensity_is_scalar);
    m = parse_ok("{\"type\":\"light\",\"intensity\":3}");
    assert_true(m.u.light.intensity_is_scalar && m.u.light.intensity.x == 3.f);
    m = parse_ok("{\"type\":\"light\",\"direction\":[1e-30,0,0]}");
    assert_near3(m.u.light.direction, iir_v3(1, 0, 0), 0.f);

    expect("{\"type\":\"light\"}", IIRD_E_BAD_FIELD, "light");
    expect("{\"type\":\"light\",\"seq\":4}", IIRD_E_BAD_FIELD, "light");
    const char *P = "{\"type\":\"light\",\"position\":%s}";
    struct {
        const char *v;
        iird_err code;
        const char *field;
    } cases[] = {
        {"[1,2]", IIRD_E_BAD_TYPE, "light.position"},
        {"[1,2,3,4]", IIRD_E_BAD_TYPE, "light.position"},
        {"[]", IIRD_E_BAD_TYPE, "light.position"},
        {"\"abc\"", IIRD_E_BAD_TYPE, "light.position"},
        {"{\"x\":1}", IIRD_E_BAD_TYPE, "light.position"},
        {"5", IIRD_E_BAD_TYPE, "light.position"},
        {"null", IIRD_E_BAD_TYPE, "light.position"},
        {"[1,\"2\",3]", IIRD_E_BAD_TYPE, "light.position[1]"},
        {"[1,2,null]", IIRD_E_BAD_TYPE, "light.position[2]"},
        {"[[1],2,3]", IIRD_E_BAD_TYPE, "light.position[0]"},
        {"[1,1e400,3]", IIRD_E_OUT_OF_RANGE, "light.position[1]"},
        {"[-1e400,0,3]", IIRD_E_OUT_OF_RANGE, "light.position[0]"},
        {"[0,0,1e308]", IIRD_E_OUT_OF_RANGE, "light.position[2]"},
        {"[0,2e6,0]", IIRD_E_OUT_OF_RANGE, "light.position[1]"},
        {"[0,0,-1000000.1]", IIRD_E_OUT_OF_RANGE, "light.position[2]"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char json[200];
        snprintf(json, sizeof json, P, cases[i].v);
        expect(json, cases[i].code, cases[i].field);
    }
    expect("{\"type\":\"light\",\"direction\":[0,0,0]}", IIRD_E_OUT_OF_RANGE, "light.direction");
    expect("{\"type\":\"light\",\"direction\":[0,-0,0]}", IIRD_E_OUT_OF_RANGE, "light.direction");
    expect("{\"type\":\"light\",\"direction\":[0,-1,0],\"target\":[0,0,0]}", IIRD_E_BAD_FIELD,
           "light.target");
    expect("{\"type\":\"light\",\"target\":[0,0]}", IIRD_E_BAD_TYPE, "light.target");
    expect("{\"type\":\"light\",\"cone_angle\":0}", IIRD_E_OUT_OF_RANGE, "light.cone_angle");
    expect("{\"type\":\"light\",\"cone_angle\":-5}", IIRD_E_OUT_OF_RANGE, "light.cone_angle");
    expect("{\"type\":\"light\",\"cone_angle\":90.0001}", IIRD_E_OUT_OF_RANGE, "light.cone_angle");
    expect("{\"type\":\"light\",\"cone_angle\":1e400}", IIRD_E_OUT_OF_RANGE, "light.cone_angle");
    expect("{\"type\":\"light\",\"cone_angle\":\"30\"}", IIRD_E_BAD_TYPE, "light.cone_angle");
    expect("{\"type\":\"light\",\"cone_angle\":[30]}", IIRD_E_BAD_TYPE, "light.cone_angle");
    expect("{\"type\":\"light\",\"intensity\":-1}", IIRD_E_OUT_OF_RANGE, "light.intensity");
    expect("{\"type\":\"light\",\"intensity\":2e6}", IIRD_E_OUT_OF_RANGE, "light.intensity");
    expect("{\"type\":\"light\",\"intensity\":[1,-1,0]}", IIRD_E_OUT_OF_RANGE,
           "light.intensity[1]");
    expect("{\"type\":\"light\",\"intensity\":[1,1,1e400]}", IIRD_E_OUT_OF_RANGE,
           "light.intensity[2]");
    expect("{\"type\":\"light\",\"intensity\":[1,1]}", IIRD_E_BAD_TYPE, "light.intensity");
    expect("{\"type\":\"light\",\"intensity\":true}", IIRD_E_BAD_TYPE, "light.intensity");
    expect("{\"type\":\"light\",\"intensity\":\"2\"}", IIRD_E_BAD_TYPE, "light.intensity");
}

static iird_proto_error apply_light_err(const char *json, iir_light *L, iird_err code,
                                        const char *field)
{
    iird_msg m = parse_ok(json);
    iird_proto_error e;
    iir_light before = *L;
    if (iird_apply_light(&m.u.light, L, &e)) fail_msg("%s: applied, expected an error", json);
    if (e.code != code || strcmp(e.field, field) != 0)
        fail_msg("%s: got %s at '%s' (%s)", json, iird_err_name(e.code), e.field, e.message);
    assert_memory_equal(&before, L, sizeof before); /* all or nothing */
    return e;
}

static void apply_light_ok(const char *json, iir_light *L)
{
    iird_msg m = parse_ok(json);
    iird_proto_error e;
    if (!iird_apply_light(&m.u.light, L, &e)) fail_msg("%s: %s", json, e.message);
    iir_error ie;
    assert_int_equal(iir_light_validate(L, &ie), IIR_OK);
}

static void test_light_apply(void **state)
{
    (void)state;
    iir_light L = spot();
    /* position alone keeps the direction; target aims from the new position */
    apply_light_ok("{\"type\":\"light\",\"position\":[1,1,0]}", &L);
    assert_near3(L.position, iir_v3(1, 1, 0), 0.f);
    assert_near3(L.direction, iir_v3(0, -1, 0), 0.f);
    apply_light_ok("{\"type\":\"light\",\"position\":[0,2,0],\"target\":[3,2,4]}", &L);
    assert_near3(L.direction, iir_v3(0.6f, 0.f, 0.8f), 1e-6f);
    apply_light_ok("{\"type\":\"light\",\"target\":[0,0,0]}", &L);
    assert_near3(L.direction, iir_v3(0, -1, 0), 1e-6f);
    apply_light_ok("{\"type\":\"light\",\"direction\":[3,0,4]}", &L);
    assert_near3(L.direction, iir_v3(0.6f, 0.f, 0.8f), 1e-6f);
    assert_near3(L.position, iir_v3(0, 2, 0), 0.f);
    /* target on the (new or current) position */
    apply_light_err("{\"type\":\"light\",\"target\":[0,2,0]}", &L, IIRD_E_BAD_FIELD,
                    "light.target");
    apply_light_err("{\"type\":\"light\",\"position\":[5,5,5],\"target\":[5,5,5],\"intensity\":1}",
                    &L, IIRD_E_BAD_FIELD, "light.target");
    /* the cone: degrees to radians; smooth is kept within it */
    assert_true(L.smooth > iir_radians(4.9f));
    apply_light_ok("{\"type\":\"light\",\"cone_angle\":30}", &L);
    assert_float_equal(L.cone_angle, iir_radians(30.f), 1e-7f);
    assert_float_equal(L.smooth, iir_radians(5.f), 1e-7f);
    apply_light_ok("{\"type\":\"light\",\"cone_angle\":2}", &L);
    assert_float_equal(L.smooth, L.cone_angle, 0.f);
    apply_light_ok("{\"type\":\"light\",\"cone_angle\":90}", &L);
    assert_true(L.cone_angle <= IIR_PI * 0.5f);
    /* intensity: a number scales the colour so its largest channel equals it */
    L = spot();
    apply_light_ok("{\"type\":\"light\",\"intensity\":2}", &L);
    assert_true(L.intensity.x == 2.f);
    assert_float_equal(L.intensity.y, 1.f, 1e-6f);
    assert_float_equal(L.intensity.z, 0.5f, 1e-6f);
    L.intensity = iir_v3(0.1f, 0.3f, 0.7f);
    apply_light_ok("{\"type\":\"light\",\"intensity\":10}", &L);
    assert_true(L.intensity.z == 10.f);
    assert_float_equal(L.intensity.x, 10.f / 7.f, 1e-5f);
    apply_light_ok("{\"type\":\"light\",\"intensity\":0}", &L);
    assert_true(iir_is_black(L.intensity));
    apply_light_ok("{\"type\":\"light\",\"intensity\":3}", &L); /* black becomes grey */
    assert_near3(L.intensity, iir_v3s(3.f), 0.f);
    apply_light_ok("{\"type\":\"light\",\"intensity\":[1,2,3]}", &L);
    assert_near3(L.intensity, iir_v3(1, 2, 3), 0.f);
    /* a broken current light: the validator's failure names a field, nothing changes */
    L = spot();
    L.cone_angle = NAN;
    apply_light_err("{\"type\":\"light\",\"intensity\":[1,1,1]}", &L, IIRD_E_OUT_OF_RANGE,
                    "light.cone_angle");
    L = spot();
    L.smooth = iir_radians(80.f);
    apply_light_err("{\"type\":\"light\",\"position\":[0,1,0]}", &L, IIRD_E_BAD_FIELD,
                    "light.cone_angle");
    L = spot();
    L.direction = iir_v3(0, 0, 0);
    apply_light_err("{\"type\":\"light\",\"position\":[0,1,0]}", &L, IIRD_E_BAD_FIELD,
                    "light.direction");
}

static void test_camera(void **state)
{
    (void)state;
    iird_msg m = parse_ok("{\"type\":\"camera\",\"fov\":170}");
    assert_true(m.u.camera.has == (1u << IIRD_C_FOV) && m.u.camera.fov == 170.f);
    m = parse_ok("{\"type\":\"camera\"}");
    assert_int_equal(m.u.camera.has, 0);
    expect("{\"type\":\"camera\",\"fov\":0.5}", IIRD_E_OUT_OF_RANGE, "camera.fov");
    expect("{\"type\":\"camera\",\"fov\":170.5}", IIRD_E_OUT_OF_RANGE, "camera.fov");
    expect("{\"type\":\"camera\",\"fov\":true}", IIRD_E_BAD_TYPE, "camera.fov");
    expect("{\"type\":\"camera\",\"up\":[0,0,0]}", IIRD_E_OUT_OF_RANGE, "camera.up");
    expect("{\"type\":\"camera\",\"up\":[0,1]}", IIRD_E_BAD_TYPE, "camera.up");
    expect("{\"type\":\"camera\",\"target\":[0,1,1e400]}", IIRD_E_OUT_OF_RANGE, "camera.target[2]");
    expect("{\"type\":\"camera\",\"position\":[0,\"1\",0]}", IIRD_E_BAD_TYPE, "camera.position[1]");

    iir_camera C = cam(), before;
    iird_proto_error e;
    m = parse_ok("{\"type\":\"camera\",\"position\":[1,2,3],\"target\":[0,0,0],\"fov\":60}");
    assert_true(iird_apply_camera(&m.u.camera, &C, &e));
    assert_near3(C.position, iir_v3(1, 2, 3), 0.f);
    assert_true(C.fov_y == 60.f);
    struct {
        const char *json;
        iird_err code;
        const char *field;
    } bad[] = {
        {"{\"type\":\"camera\",\"target\":[1,2,3]}", IIRD_E_BAD_FIELD, "camera.target"},
        {"{\"type\":\"camera\",\"position\":[0,0,0]}", IIRD_E_BAD_FIELD, "camera.position"},
        {"{\"type\":\"camera\",\"up\":[1,2,3]}", IIRD_E_BAD_FIELD, "camera.up"},
        {"{\"type\":\"camera\",\"up\":[-2,-4,-6],\"fov\":50}", IIRD_E_BAD_FIELD, "camera.up"},
        {"{\"type\":\"camera\",\"position\":[0,5,0],\"target\":[0,0,0]}", IIRD_E_BAD_FIELD,
         "camera.up"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        m = parse_ok(bad[i].json);
        before = C;
        if (iird_apply_camera(&m.u.camera, &C, &e)) fail_msg("%s applied", bad[i].json);
        if (e.code != bad[i].code || strcmp(e.field, bad[i].field) != 0)
            fail_msg("%s: %s at '%s'", bad[i].json, iird_err_name(e.code), e.field);
        assert_memory_equal(&before, &C, sizeof C);
    }
    m = parse_ok("{\"type\":\"camera\",\"position\":[0,5,0],\"target\":[0,0,0],\"up\":[0,0,-1]}");
    assert_true(iird_apply_camera(&m.u.camera, &C, &e));
}

/* ======================== params ======================== */

/* Every params field, from the tables: the stream settings' and every method's rows. */
static void each_param_row(void (*fn)(const iir_param *row))
{
    for (int i = 0; i < iird_stream_table.count; i++) fn(&iird_stream_table.rows[i]);
    for (const iir_param_table *const *t = iir_method_all_tables(); *t; t++)
        for (int i = 0; i < (*t)->count; i++) fn(&(*t)->rows[i]);
}

/* A row's accepted bounds and out-of-range and wrongly typed values, parsed as the protocol says:
 * numbers up to the live maximum (width/height: up to LIM), enum names, booleans. */
static void check_param_row(const iir_param *row)
{
    char json[256], field[64], lo[40], hi[40];
    snprintf(field, sizeof field, "params.%s", row->name);
    double top = iir_param_max(row, true); /* width, height: the limits apply later */
    if (row->type == IIR_PARAM_ENUM) {
        snprintf(lo, sizeof lo, "\"%s\"", row->choices[0]);
        snprintf(hi, sizeof hi, "\"%s\"", row->choices[(int)row->hi]);
    } else if (row->type == IIR_PARAM_BOOL) {
        snprintf(lo, sizeof lo, "false"), snprintf(hi, sizeof hi, "true");
    } else {
        snprintf(lo, sizeof lo, "%.17g", row->lo), snprintf(hi, sizeof hi, "%.17g", top);
    }
    const char *ok[] = {lo, hi};
    for (int k = 0; k < 2; k++) {
        snprintf(json, sizeof json, "{\"type\":\"params\",\"%s\":%s}", row->name, ok[k]);
        iird_msg m = parse_ok(json);
        assert_true(iir_params_has(&m.u.params.values, row->name));
        assert_int_equal(m.u.params.values.count, 1);
    }
    if (row->type == IIR_PARAM_ENUM) {
        snprintf(json, sizeof json, "{\"type\":\"params\",\"%s\":\"nope\"}", row->name);
        iird_proto_error e = expect(json, IIRD_E_OUT_OF_RANGE, field);
        for (int i = 0; row->choices[i]; i++) assert_non_null(strstr(e.message, row->choices[i]));
    } else if (row->type != IIR_PARAM_BOOL) {
        snprintf(json, sizeof json, "{\"type\":\"params\",\"%s\":%.17g}", row->name,
                 row->lo - (row->type == IIR_PARAM_FLOAT ? 0.5 : 1.0));
        expect(json, IIRD_E_OUT_OF_RANGE, field);
        snprintf(json, sizeof json, "{\"type\":\"params\",\"%s\":%.17g}", row->name,
                 top + (row->type == IIR_PARAM_FLOAT ? 0.5 : 2.0));
        expect(json, IIRD_E_OUT_OF_RANGE, field);
    }
    snprintf(json, sizeof json, "{\"type\":\"params\",\"%s\":%s}", row->name,
             row->type == IIR_PARAM_BOOL   ? "1"
             : row->type == IIR_PARAM_ENUM ? "1"
                                           : "\"1\"");
    expect(json, IIRD_E_BAD_TYPE, field);
    if (row->type == IIR_PARAM_INT || row->type == IIR_PARAM_U64) {
        snprintf(json, sizeof json, "{\"type\":\"params\",\"%s\":%.17g}", row->name, row->lo + 0.5);
        expect(json, IIRD_E_BAD_TYPE, field);
    }
    snprintf(json, sizeof json, "{\"type\":\"params\",\"%s\":1e400}", row->name);
    iird_msg m;
    iird_proto_error e;
    assert_false(iird_parse_message(json, strlen(json), &LIM, &m, &e));
    assert_string_equal(e.field, field);
}

static void test_params_parse(void **state)
{
    (void)state;
    each_param_row(check_param_row);
    iird_msg m = parse_ok("{\"type\":\"params\",\"method\":\"pt\"}");
    assert_true(m.u.params.has_method);
    assert_string_equal(m.u.params.method, "pt");
    iird_proto_error e =
        expect("{\"type\":\"params\",\"method\":\"foo\"}", IIRD_E_OUT_OF_RANGE, "params.method");
    for (const char *const *n = iir_method_names(); *n; n++) assert_non_null(strstr(e.message, *n));
    expect("{\"type\":\"params\",\"method\":3}", IIRD_E_BAD_TYPE, "params.method");
    /* values land under their names */
    m = parse_ok("{\"type\":\"params\",\"method\":\"pt\",\"vpls\":100,\"weights\":\"uniform\","
                 "\"clamp\":0.5,\"width\":640,\"refine\":false,\"seed\":9007199254740991}");
    const iir_params *v = &m.u.params.values;
    double x = 0;
    assert_true(iir_params_get(v, "vpls", &x) && x == 100);
    assert_true(iir_params_get(v, "weights", &x) && x == 0);
    assert_true(iir_params_get(v, "clamp", &x) && x == 0.5);
    assert_true(iir_params_get(v, "width", &x) && x == 640);
    assert_true(iir_params_get(v, "refine", &x) && x == 0);
    assert_true(iir_params_get(v, "seed", &x) && x == 9007199254740991.0);
    assert_int_equal(v->count, 6);
    /* live maxima bound what a client may ask for: more VPLs than a frame stays interactive */
    e = expect("{\"type\":\"params\",\"vpls\":4097}", IIRD_E_OUT_OF_RANGE, "params.vpls");
    assert_non_null(strstr(e.message, "4096"));
    expect("{\"type\":\"params\",\"spp\":65}", IIRD_E_OUT_OF_RANGE, "params.spp");
    /* integers above 2^53 - 1 cannot be told apart as doubles: refused, with exact digits */
    e = expect("{\"type\":\"params\",\"seed\":9007199254740992}", IIRD_E_OUT_OF_RANGE,
               "params.seed");
    assert_non_null(strstr(e.message, "9007199254740991], got 9007199254740992"));
    expect("{\"type\":\"params\",\"seed\":9007199254740993}", IIRD_E_OUT_OF_RANGE, "params.seed");
}

static double val(const iird_settings *s, const char *name)
{
    return iir_method_param_value(iir_method_any_param(name), &s->params);
}

static void test_params_apply(void **state)
{
    (void)state;
    iird_settings s = iird_settings_default(), before;
    iird_proto_error e;
    assert_string_equal(s.method, "iir");
    /* a live session starts at each row's one default: pt at 1 sample per pixel */
    assert_true(val(&s, "bounces") == 2 && val(&s, "spp") == 1 && s.width == 512 &&
                s.height == 384);
    assert_true(s.quality == 80 && s.exposure == 0.f && s.refine && s.domain);
    iir_error ie;
    assert_int_equal(iir_method_params_validate("iir", &s.params, NULL, NULL, &ie), IIR_OK);

    iird_msg m = parse_ok("{\"type\":\"params\",\"vpls\":64,\"kmax\":6,\"exposure\":1}");
    assert_true(iird_apply_params(&m.u.params, &LIM, &s, &e));
    assert_true(val(&s, "vpls") == 64 && val(&s, "kmax") == 6 && val(&s, "kmin") == 4);
    assert_true(s.exposure == 1.f && s.width == 512);

    struct {
        const char *json;
        iird_err code;
        const char *field;
    } bad[] = {
        {"{\"type\":\"params\",\"kmin\":7}", IIRD_E_BAD_FIELD, "params.kmin"},
        {"{\"type\":\"params\",\"kmax\":3}", IIRD_E_BAD_FIELD, "params.kmax"},
        {"{\"type\":\"params\",\"kmin\":9,\"kmax\":8}", IIRD_E_BAD_FIELD, "params.kmin"},
        {"{\"type\":\"params\",\"kmax\":65}", IIRD_E_BAD_FIELD, "params.kmax"},
        {"{\"type\":\"params\",\"vpls\":5}", IIRD_E_BAD_FIELD, "params.vpls"},
        /* one bad field among good ones: nothing of it is applied */
        {"{\"type\":\"params\",\"vpls\":100,\"quality\":10,\"kmin\":50,\"kmax\":10}",
         IIRD_E_BAD_FIELD, "params.kmin"},
        {"{\"type\":\"params\",\"width\":1000,\"method\":\"pt\"}", IIRD_E_OUT_OF_RANGE,
         "params.width"},
        {"{\"type\":\"params\",\"height\":600}", IIRD_E_OUT_OF_RANGE, "params.height"},
    };
    iird_limits small = {.max_width = 640, .max_height = 480};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        m = parse_ok(bad[i].json);
        before = s;
        if (iird_apply_params(&m.u.params, &small, &s, &e)) fail_msg("%s applied", bad[i].json);
        if (e.code != bad[i].code || strcmp(e.field, bad[i].field) != 0)
            fail_msg("%s: %s at '%s' (%s)", bad[i].json, iird_err_name(e.code), e.field, e.message);
        assert_memory_equal(&before, &s, sizeof s);
    }
    /* a parameter set earlier for another method is checked when its method is chosen */
    m = parse_ok("{\"type\":\"params\",\"spp\":64}");
    assert_true(iird_apply_params(&m.u.params, &LIM, &s, &e));
    m = parse_ok("{\"type\":\"params\",\"method\":\"pt\"}");
    assert_true(iird_apply_params(&m.u.params, &LIM, &s, &e));
    assert_true(val(&s, "spp") == 64 && !strcmp(s.method, "pt"));
    /* every field at once */
    s = iird_settings_default();
    m = parse_ok("{\"type\":\"params\",\"method\":\"pt\",\"vpls\":10,\"kmin\":0,\"kmax\":10,"
                 "\"seed\":42,\"refine_passes\":4096,\"width\":1920,\"height\":1080}");
    assert_true(iird_apply_params(&m.u.params, &LIM, &s, &e));
    assert_string_equal(s.method, "pt");
    assert_true(val(&s, "seed") == 42 && val(&s, "refine_passes") == 4096 && s.width == 1920);
    /* parse errors also leave the settings alone: the message never reaches apply */
    expect("{\"type\":\"params\",\"vpls\":64,\"kmax\":3.5}", IIRD_E_BAD_TYPE, "params.kmax");
}

/* ======================== recording ======================== */

static void test_recording_round_trip(void **state)
{
    (void)state;
    iird_recording *r = iird_recording_create(24, "kitchen", "/srv/iir scenes");
    assert_non_null(r);
    iird_recording_set_size(r, 640, 360);
    iird_recording_set_size(r, 512, 384); /* the last size set */
    iird_proto_error e;
    enum { N = 7 };
    const double ts[N] = {0.0, 0.1, 0.35, 1.0, 1.0000001, 2.5, 3.25};
    iir_light rec[N];
    for (int i = 0; i < N; i++) {
        iir_light L = spot();
        L.position = iir_v3(0.1f * (float)i - 0.3f, 1.9f - 0.05f * (float)i, 0.13f * (float)i);
        L.direction =
            iir_normalize(iir_v3(0.2f * sinf((float)i), -1.f, 0.3f * cosf(1.7f * (float)i)));
        L.cone_angle = iir_radians(20.f + 10.f * (float)i);
        L.smooth = i == 3 ? L.cone_angle : iir_radians(1.f + (float)i);
        L.intensity = iir_v3(1.f + (float)i, 0.5f, 0.1f * (float)i);
        if (i == 6) L.cone_angle = iir_radians(90.f);
        rec[i] = L;
        assert_true(iird_recording_add(r, ts[i], &L, &e));
    }
    /* ts[4] is within a microsecond of ts[3]: it replaced key 3 */
    rec[3] = rec[4];
    char *text = iird_json_record_stop(r, 8);
    cJSON *o = reply_ok(text, "record");
    assert_int_equal(num(o, "seq"), 8);
    assert_int_equal(num(o, "keyframes"), N - 1);
    assert_true(num(o, "duration") == 3.25);
    char *script = cJSON_PrintUnformatted(cJSON_GetObjectItemCaseSensitive(o, "script"));
    assert_non_null(strstr(script, "\"interpolation\":\"linear\""));
    assert_non_null(strstr(script, "\"fps\":24"));
    iir_anim *a = NULL;
    iir_error ie;
    if (iir_anim_parse(script, "recording", &a, &ie) != IIR_OK) fail_msg("%s\n%s", ie.msg, script);
    assert_true(iir_anim_duration(a) == 3.25 && iir_anim_fps(a) == 24.0);
    /* where and how it was made: the scene, its folder, the session's frame size */
    int w = 0, h = 0;
    assert_string_equal(iir_anim_scene(a), "kitchen");
    assert_string_equal(iir_anim_scenes_dir(a), "/srv/iir scenes");
    assert_true(iir_anim_size(a, &w, &h) && w == 512 && h == 384);
    iir_light base = spot();
    base.position = iir_v3(9, 9, 9);
    base.smooth = 0.f;
    for (int i = 0; i < N; i++) {
        if (i == 4) continue;
        iir_light got = iir_anim_light(a, &base, ts[i]);
        assert_near3(got.position, rec[i].position, 1e-6f);
        assert_near3(got.direction, rec[i].direction, 1e-6f);
        assert_near3(got.intensity, rec[i].intensity, 1e-6f);
        assert_float_equal(got.cone_angle, rec[i].cone_angle, 1e-6f);
        assert_float_equal(got.smooth, rec[i].smooth, 1e-6f);
        assert_int_equal(iir_light_validate(&got, &ie), IIR_OK);
    }
    /* the script alone is the same text */
    char *alone = iird_recording_script(r);
    assert_string_equal(alone, script);
    free(alone);
    free(script);
    iir_anim_destroy(a);
    cJSON_Delete(o);
    iird_recording_destroy(r);

    /* one key at t = 0: the script lasts one frame; no key: no light track */
    r = iird_recording_create(30, NULL, NULL);
    iir_light L = spot();
    assert_true(iird_recording_add(r, 0.0, &L, &e));
    script = iird_recording_script(r);
    assert_int_equal(iir_anim_parse(script, "one", &a, &ie), IIR_OK);
    assert_float_equal(iir_anim_duration(a), 1.0 / 30.0, 1e-12);
    assert_true(iir_anim_has_light(a));
    assert_false(iir_anim_size(a, &w, &h)); /* no size set: none named */
    assert_string_equal(iir_anim_scenes_dir(a), "");
    iir_anim_destroy(a);
    free(script);
    iird_recording_destroy(r);
    r = iird_recording_create(30, NULL, NULL);
    script = iird_recording_script(r);
    assert_int_equal(iir_anim_parse(script, "empty", &a, &ie), IIR_OK);
    assert_false(iir_anim_has_light(a));
    iir_anim_destroy(a);
    free(script);
    o = reply_ok(iird_json_record_stop(r, IIRD_NO_SEQ), "record");
    assert_null(cJSON_GetObjectItemCaseSensitive(o, "seq"));
    assert_int_equal(num(o, "keyframes"), 0);
    cJSON_Delete(o);
    /* limits: 36000 s and 100000 keyframes */
    assert_false(iird_recording_add(r, 36000.5, &L, &e));
    assert_int_equal(e.code, IIRD_E_TOO_LARGE);
    for (int i = 0; i < 100000; i++) assert_true(iird_recording_add(r, i * 0.01, &L, &e));
    assert_true(iird_recording_add(r, 999.99, &L, &e)); /* same time: replaces the last */
    assert_false(iird_recording_add(r, 1000.5, &L, &e));
    assert_int_equal(e.code, IIRD_E_TOO_LARGE);
    assert_false(iird_recording_add(r, NAN, &L, &e));
    assert_int_equal(e.code, IIRD_E_INTERNAL);
    /* (the script of 100000 keys is not built here: 15 MB of JSON take seconds under ASan, and
     * iir_anim_parse reads keys in quadratic time, minutes for 100000) */
    iird_recording_destroy(r);

    o = reply_ok(iird_json_record_start(7), "record");
    assert_int_equal(num(o, "seq"), 7);
    assert_true(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(o, "recording")));
    cJSON_Delete(o);
}

/* A session's four lights: a cosine spot, a glTF spot, a point light and a sun. */
static void four_lights(iir_light L[4])
{
    L[0] = spot();
    L[1] = spot();
    snprintf(L[1].name, sizeof L[1].name, "gltf");
    L[1].profile = IIR_SPOT_GLTF;
    L[1].smooth = 0.f;
    L[1].inner_angle = iir_radians(15.f);
    L[2] = (iir_light){.type = IIR_LIGHT_POINT, .name = "lamp", .intensity = {1.f, 1.f, 0.5f}};
    L[2].position = iir_v3(0.4f, 1.f, 0.2f);
    L[3] = (iir_light){.type = IIR_LIGHT_SUN, .name = "sun", .radius = 2.f};
    L[3].position = iir_v3(0.f, 1.f, 0.f);
    L[3].direction = iir_normalize(iir_v3(0.3f, -1.f, 0.1f));
    L[3].up = iir_v3(0.f, 1.f, 0.f);
    L[3].intensity = iir_v3s(3.f);
}

/* Every light recorded at once (iird_recording_add_lights) replays offline to the same lights:
 * the script's "lights" tracks give each kind's fields, a light switched off (black) is off at
 * its key and keeps the intensity it had, a sun keeps its disk; the lights cannot change within
 * a recording; a recording of one light still works beside it (test above). */
static void test_recording_lights(void **state)
{
    (void)state;
    iird_recording *r = iird_recording_create(10, "builtin", NULL);
    iird_proto_error e;
    enum { N = 5 };
    const double ts[N] = {0.0, 0.1, 0.2, 0.7, 0.8};
    iir_light rec[N][4];
    for (int i = 0; i < N; i++) {
        four_lights(rec[i]);
        rec[i][0].position.x = 0.1f * (float)i;
        rec[i][1].inner_angle = iir_radians(5.f + 5.f * (float)i);
        rec[i][2].position.y = 1.f - 0.1f * (float)i;
        if (i == 2 || i == 3) rec[i][2].intensity = iir_v3s(0.f); /* the lamp off, then on */
        rec[i][3].direction = iir_normalize(iir_v3(0.3f - 0.2f * (float)i, -1.f, 0.1f));
        assert_true(iird_recording_add_lights(r, ts[i], rec[i], 4, &e));
    }
    char *script = iird_recording_script(r);
    assert_non_null(strstr(script, "\"inner_angle\""));
    assert_non_null(strstr(script, "\"on\":false"));
    assert_null(strstr(script, "\"light\":")); /* no light track */
    cJSON *o = reply_ok(iird_json_record_stop(r, 3), "record");
    assert_int_equal(num(o, "keyframes"), N);
    cJSON_Delete(o);
    iir_anim *a = NULL;
    iir_error ie;
    if (iir_anim_parse(script, "rec", &a, &ie) != IIR_OK) fail_msg("%s\n%s", ie.msg, script);
    iir_light base[4], got[4];
    four_lights(base);
    for (int k = 0; k < 3; k++) base[k].position = iir_v3(9, 9, 9);
    if (iir_anim_check_lights(a, base, 4, 0, &ie) != IIR_OK) fail_msg("%s", ie.msg);
    for (int i = 0; i < N; i++) {
        iir_anim_lights(a, base, 4, 0, ts[i], got);
        for (int k = 0; k < 4; k++) {
            const iir_light *want = &rec[i][k];
            assert_near3(got[k].position, k == 3 ? base[3].position : want->position, 1e-6f);
            assert_near3(got[k].direction, want->direction, 1e-6f);
            assert_near3(got[k].intensity, want->intensity, 1e-6f);
            assert_float_equal(got[k].inner_angle, want->inner_angle, 1e-6f);
            assert_float_equal(got[k].smooth, want->smooth, 1e-6f);
            assert_int_equal(iir_light_validate(&got[k], &ie), IIR_OK);
        }
    }
    /* between the off key and the next on key: off; before the off key: the lit intensity */
    iir_anim_lights(a, base, 4, 0, 0.5, got);
    assert_near3(got[2].intensity, iir_v3s(0.f), 0.f);
    iir_anim_lights(a, base, 4, 0, 0.15, got);
    assert_near3(got[2].intensity, rec[0][2].intensity, 1e-6f);
    iir_anim_destroy(a);
    free(script);
    /* other lights: refused, the recording unchanged */
    assert_false(iird_recording_add_lights(r, 1.0, rec[0], 3, &e));
    assert_int_equal(e.code, IIRD_E_INTERNAL);
    iir_light renamed[4];
    four_lights(renamed);
    snprintf(renamed[2].name, sizeof renamed[2].name, "other");
    assert_false(iird_recording_add_lights(r, 1.0, renamed, 4, &e));
    o = reply_ok(iird_json_record_stop(r, 4), "record");
    assert_int_equal(num(o, "keyframes"), N);
    cJSON_Delete(o);
    iird_recording_destroy(r);
}

/* ======================== frames ======================== */

static void test_frame_header(void **state)
{
    (void)state;
    iird_frame_header h = {.kind = 1,
                           .frame_id = 0x01020304u,
                           .seq = 0xFFFFFFFFu,
                           .width = 512,
                           .height = 0x0180,
                           .render_ms = 1.5f,
                           .encode_ms = -2.f,
                           .pass = 7,
                           .flags = 3,
                           .payload_bytes = 0xA0B0C0D0u,
                           .generation = 0x0A0B0C0Du};
    uint8_t b[IIRD_FRAME_HEADER_BYTES];
    memset(b, 0xEE, sizeof b);
    iird_frame_header_write(&h, b);
    const uint8_t want[IIRD_FRAME_HEADER_BYTES] = {
        'I',  'I',  'R',  'F',  1,    2,    44,   0,    0x04, 0x03, 0x02, 0x01, 0xFF, 0xFF, 0xFF,
        0xFF, 0x00, 0x02, 0x80, 0x01, 0x00, 0x00, 0xC0, 0x3F, 0x00, 0x00, 0x00, 0xC0, 7,    0,
        0,    0,    3,    0,    0,    0,    0xD0, 0xC0, 0xB0, 0xA0, 0x0D, 0x0C, 0x0B, 0x0A};
    assert_memory_equal(b, want, sizeof want);
}

/* ======================== replies ======================== */

static void test_json_replies(void **state)
{
    (void)state;
    /* error: seq only when valid, field null when none */
    iird_proto_error pe;
    pe.seq = 5;
    iird_proto_fail(&pe, IIRD_E_OUT_OF_RANGE, "light.cone_angle",
                    "light.cone_angle must be in "
                    "(0, 90] degrees, got 120");
    cJSON *o = reply_ok(iird_json_error(&pe), "error");
    assert_int_equal(num(o, "seq"), 5);
    assert_string_equal(cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(o, "code")),
                        "out_of_range");
    assert_string_equal(cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(o, "field")),
                        "light.cone_angle");
    assert_non_null(
        strstr(cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(o, "message")), "got 120"));
    cJSON_Delete(o);
    pe.seq = IIRD_NO_SEQ;
    iird_proto_fail(&pe, IIRD_E_BUSY, NULL, "too many sessions (%d)", 4);
    o = reply_ok(iird_json_error(&pe), "error");
    assert_null(cJSON_GetObjectItemCaseSensitive(o, "seq"));
    assert_true(cJSON_IsNull(cJSON_GetObjectItemCaseSensitive(o, "field")));
    cJSON_Delete(o);
    for (int c = 0; c < IIRD_E_COUNT; c++) assert_true(strlen(iird_err_name((iird_err)c)) > 3);
    assert_string_equal(iird_err_name(IIRD_E_RATE_LIMITED), "rate_limited");
    assert_string_equal(iird_err_name(IIRD_E_SCENE_ERROR), "scene_error");

    /* state: documented keys, compact numbers */
    iir_light L = spot();
    iir_camera C = cam();
    iird_settings s = iird_settings_default();
    iir_error ie;
    assert_int_equal(
        iir_params_set(&s.params, iir_method_any_param("seed"), 9007199254740991.0, &ie), IIR_OK);
    iird_state_view v = {"builtin", &L, &C, &s, 4, false, NULL, NULL, NULL, 0};
    char *text = iird_json_state(&v, 3);
    assert_non_null(strstr(text, "\"fov\":39.3}"));
    assert_non_null(strstr(text, "\"cone_angle\":60,"));
    assert_non_null(strstr(text, "\"generation\":4,"));
    assert_non_null(strstr(text, "\"default_light\":false,"));
    assert_non_null(strstr(text, "\"position\":[0,1.9,0]"));
    assert_non_null(strstr(text, "\"seed\":9007199254740991"));
    o = reply_ok(text, "state");
    assert_int_equal(num(o, "seq"), 3);
    assert_string_equal(cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(o, "scene")),
                        "builtin");
    const cJSON *jl = cJSON_GetObjectItemCaseSensitive(o, "light");
    assert_near3(vec(jl, "direction"), L.direction, 0.f);
    assert_near3(vec(jl, "intensity"), L.intensity, 0.f);
    const cJSON *jc = cJSON_GetObjectItemCaseSensitive(o, "camera");
    assert_near3(vec(jc, "target"), C.target, 0.f);
    assert_near3(vec(jc, "up"), C.up, 0.f);
    const cJSON *jp = cJSON_GetObjectItemCaseSensitive(o, "params");
    /* method, the stream settings and every parameter of the session's method */
    int rows = 1 + iird_stream_table.count;
    for (const iir_param_table *const *t = iir_method_tables(s.method); *t; t++) {
        rows += (*t)->count;
        for (int i = 0; i < (*t)->count; i++)
            assert_non_null(cJSON_GetObjectItemCaseSensitive(jp, (*t)->rows[i].name));
    }
    assert_int_equal(cJSON_GetArraySize(jp), rows);
    assert_string_equal(cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(jp, "weights")),
                        "surface");
    assert_int_equal(num(jp, "vpls"), 256);
    assert_int_equal(num(jp, "width"), 512);
    assert_true(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(jp, "refine")));
    cJSON_Delete(o);
    /* a state reply reads back as a params message that changes nothing (a seed below 1e15:
     * cJSON would print a larger one back rounded) */
    assert_int_equal(iir_params_set(&s.params, iir_method_any_param("seed"), 123456789, &ie),
                     IIR_OK);
    text = iird_json_state(&v, IIRD_NO_SEQ);
    char *was = iird_json_state(&v, IIRD_NO_SEQ);
    o = cJSON_Parse(text);
    free(text);
    cJSON *params = cJSON_DetachItemFromObjectCaseSensitive(o, "params");
    cJSON_AddStringToObject(params, "type", "params");
    text = cJSON_PrintUnformatted(params);
    iird_msg m = parse_ok(text);
    iird_settings s2 = s;
    assert_true(iird_apply_params(&m.u.params, &LIM, &s2, &pe));
    iird_state_view v2 = {"builtin", &L, &C, &s2, 4, false, NULL, NULL, NULL, 0};
    char *now = iird_json_state(&v2, IIRD_NO_SEQ);
    assert_string_equal(was, now);
    free(was);
    free(now);
    free(text);
    cJSON_Delete(params);
    cJSON_Delete(o);

    /* welcome */
    const char *scenes[] = {"builtin", "cornell_box", NULL};
    o = reply_ok(iird_json_welcome(&v, 7, scenes, 0, &LIM, 0), "welcome");
    assert_int_equal(num(o, "protocol"), 1);
    assert_int_equal(num(o, "session"), 7);
    assert_int_equal(num(o, "seq"), 0);
    assert_non_null(
        strstr(cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(o, "server")), "iird "));
    const cJSON *js = cJSON_GetObjectItemCaseSensitive(o, "scenes");
    assert_int_equal(cJSON_GetArraySize(js), 2);
    assert_string_equal(cJSON_GetArrayItem(js, 1)->valuestring, "cornell_box");
    const cJSON *jm = cJSON_GetObjectItemCaseSensitive(o, "methods");
    int k = 0;
    for (const char *const *n = iir_method_names(); *n; n++, k++) {
        const cJSON *e = cJSON_GetArrayItem(jm, k);
        assert_string_equal(cJSON_GetObjectItemCaseSensitive(e, "name")->valuestring, *n);
        assert_true(strlen(cJSON_GetObjectItemCaseSensitive(e, "summary")->valuestring) > 0);
        /* the method's parameters, every row of its tables with its type and range */
        const cJSON *rows = cJSON_GetObjectItemCaseSensitive(e, "params");
        int nrows = 0;
        for (const iir_param_table *const *t = iir_method_tables(*n); *t; t++)
            for (int i = 0; i < (*t)->count; i++, nrows++) {
                const cJSON *r = cJSON_GetArrayItem(rows, nrows);
                assert_string_equal(cJSON_GetObjectItemCaseSensitive(r, "name")->valuestring,
                                    (*t)->rows[i].name);
                assert_string_equal(cJSON_GetObjectItemCaseSensitive(r, "type")->valuestring,
                                    iir_param_type_name((*t)->rows[i].type));
                assert_non_null(cJSON_GetObjectItemCaseSensitive(r, "default"));
                assert_non_null(cJSON_GetObjectItemCaseSensitive(r, "help"));
            }
        assert_int_equal(cJSON_GetArraySize(rows), nrows);
    }
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(o, "settings")),
                     iird_stream_table.count);
    assert_int_equal(cJSON_GetArraySize(jm), k);
    const cJSON *jlim = cJSON_GetObjectItemCaseSensitive(o, "limits");
    assert_int_equal(num(jlim, "max_width"), 1920);
    assert_int_equal(num(jlim, "max_height"), 1080);
    assert_int_equal(num(jlim, "max_message_bytes"), 65536);
    assert_int_equal(num(jlim, "max_rate"), 250);
    const cJSON *jst = cJSON_GetObjectItemCaseSensitive(o, "state");
    assert_non_null(cJSON_GetObjectItemCaseSensitive(jst, "light"));
    assert_non_null(cJSON_GetObjectItemCaseSensitive(jst, "camera"));
    assert_non_null(cJSON_GetObjectItemCaseSensitive(jst, "params"));
    assert_string_equal(cJSON_GetObjectItemCaseSensitive(jst, "scene")->valuestring, "builtin");
    cJSON_Delete(o);

    /* stats */
    iir_frame_stats fs;
    memset(&fs, 0, sizeof fs);
    fs.total_ms = 27.91234;
    fs.phase_ms[IIR_PHASE_INDIRECT] = 13.9;
    fs.rays.n[IIR_RAYS_SHADOW] = 196608;
    fs.rays.n[IIR_RAYS_VPL] = 5000000000ull;
    fs.vpl.count = 256;
    fs.vpl.null_samples = 3;
    fs.vpl_evals = 3145728;
    fs.vpl_reused = 3047424;
    iird_stats_view sv = {.frame = 12,
                          .seq = 40,
                          .method = "iir",
                          .pass = 0,
                          .stats = &fs,
                          .encode_ms = 2.1,
                          .latency_ms = 31.0,
                          .fps = 33.2345,
                          .bytes = 41234,
                          .dropped = 1,
                          .memory_bytes = 12582912};
    text = iird_json_stats(&sv);
    assert_non_null(strstr(text, "\"total_ms\":27.912,"));
    assert_non_null(strstr(text, "\"vpl\":5000000000,"));
    o = reply_ok(text, "stats");
    assert_int_equal(num(o, "frame"), 12);
    assert_int_equal(num(o, "seq"), 40);
    assert_true(cJSON_IsFalse(cJSON_GetObjectItemCaseSensitive(o, "converged")));
    assert_true(num(o, "fps") == 33.23 && num(o, "encode_ms") == 2.1);
    assert_int_equal(num(o, "bytes"), 41234);
    assert_int_equal(num(o, "dropped"), 1);
    assert_int_equal(num(o, "memory_bytes"), 12582912);
    assert_int_equal(num(o, "vpl_evals"), 3145728);
    assert_int_equal(num(o, "vpl_reused"), 3047424);
    /* iir's declared phases, in its order, and no counters */
    const cJSON *ph = cJSON_GetObjectItemCaseSensitive(o, "phases");
    const iir_phase *declared;
    int nph = iir_method_phases("iir", &declared);
    assert_int_equal(cJSON_GetArraySize(ph), nph);
    for (int i = 0; i < nph; i++)
        assert_string_equal(cJSON_GetArrayItem(ph, i)->string, iir_phase_name(declared[i]));
    assert_true(num(ph, "indirect") == 13.9);
    assert_null(cJSON_GetObjectItemCaseSensitive(ph, "trace"));
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(o, "counters")), 0);
    const cJSON *jv = cJSON_GetObjectItemCaseSensitive(o, "vpl");
    const char *vk[] = {"count", "valid",       "invalidated", "deleted",    "inserted",
                        "null",  "regenerated", "shadowmaps",  "descendants"};
    assert_int_equal(cJSON_GetArraySize(jv), 9);
    for (int i = 0; i < 9; i++) assert_non_null(cJSON_GetObjectItemCaseSensitive(jv, vk[i]));
    assert_int_equal(num(jv, "count"), 256);
    assert_int_equal(num(jv, "null"), 3);
    const cJSON *jr = cJSON_GetObjectItemCaseSensitive(o, "rays");
    assert_int_equal(cJSON_GetArraySize(jr), IIR_RAY_KIND_COUNT);
    assert_int_equal(num(jr, "shadow"), 196608);
    cJSON_Delete(o);
    /* rsm: its phases (maps, not vpls) and its counter, a share rounded to 1e-4 */
    fs.counter[iir_method_counter_index("rsm", "recomputed")] = 0.123456;
    fs.phase_ms[IIR_PHASE_MAPS] = 0.5;
    sv.method = "rsm";
    o = reply_ok(iird_json_stats(&sv), "stats");
    ph = cJSON_GetObjectItemCaseSensitive(o, "phases");
    assert_true(num(ph, "maps") == 0.5 && !cJSON_GetObjectItemCaseSensitive(ph, "vpls"));
    assert_true(num(cJSON_GetObjectItemCaseSensitive(o, "counters"), "recomputed") == 0.1235);
    cJSON_Delete(o);

    /* pick, snapshot */
    o = reply_ok(iird_json_pick(5, true, iir_v3(0.5f, 0, -1), iir_v3(0, 1, 0), 2.25f), "pick");
    assert_true(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(o, "hit")));
    assert_near3(vec(o, "position"), iir_v3(0.5f, 0, -1), 0.f);
    assert_near3(vec(o, "normal"), iir_v3(0, 1, 0), 0.f);
    assert_true(num(o, "distance") == 2.25);
    cJSON_Delete(o);
    o = reply_ok(iird_json_pick(5, false, iir_v3s(0), iir_v3s(0), 0), "pick");
    assert_true(cJSON_IsFalse(cJSON_GetObjectItemCaseSensitive(o, "hit")));
    assert_null(cJSON_GetObjectItemCaseSensitive(o, "position"));
    cJSON_Delete(o);
    o = reply_ok(iird_json_snapshot(6, "png", 12, 9, 123456, 512, 384), "snapshot");
    assert_string_equal(cJSON_GetObjectItemCaseSensitive(o, "format")->valuestring, "png");
    assert_true(num(o, "seq") == 6 && num(o, "frame") == 12 && num(o, "pass") == 9);
    assert_true(num(o, "bytes") == 123456 && num(o, "width") == 512 && num(o, "height") == 384);
    cJSON_Delete(o);
}

static void test_json_domain(void **state)
{
    (void)state;
    const float px[3][2] = {{10.25f, 20.5f}, {-1.f, -1.f}, {511.f, 0.f}};
    const uint8_t flags[3] = {1, 0, 2};
    cJSON *o = reply_ok(iird_json_domain(12, px, flags, 3, NULL), "domain");
    assert_int_equal(num(o, "frame"), 12);
    const cJSON *vp = cJSON_GetObjectItemCaseSensitive(o, "vpls");
    assert_int_equal(cJSON_GetArraySize(vp), 3);
    const cJSON *v0 = cJSON_GetArrayItem(vp, 0);
    assert_int_equal(cJSON_GetArraySize(v0), 3);
    assert_true(cJSON_GetArrayItem(v0, 0)->valuedouble == 10.25);
    assert_true(cJSON_GetArrayItem(v0, 2)->valuedouble == 1.0);
    assert_true(cJSON_GetArrayItem(cJSON_GetArrayItem(vp, 1), 0)->valuedouble == -1.0);
    assert_null(cJSON_GetObjectItemCaseSensitive(o, "sites"));
    cJSON_Delete(o);

    const iir_domain_site sites[3] = {
        {0.f, 0.f, 4, 0}, {0.5f, 0.f, 7, IIR_SITE_NEW}, {0.f, -0.5f, 9, IIR_SITE_NULL}};
    const uint32_t edges[3][2] = {{0, 1}, {1, 2}, {0, 2}};
    const uint32_t starts[4] = {0, 3, 5, 8};
    const float pts[8][2] = {{0, 0},    {0.25f, 0}, {0, -0.25f}, {1, 0},
                             {0.3f, 0}, {0, -1},    {0.1f, 0},   {0.123456789f, 0}};
    const float removed[1][2] = {{1.5f, 0.f}};
    iir_domain dom = {3, sites, 3, edges, 3, starts, pts, 1, removed, "disk"};
    o = reply_ok(iird_json_domain(13, px, flags, 3, &dom), "domain");
    const cJSON *js = cJSON_GetObjectItemCaseSensitive(o, "sites");
    assert_int_equal(cJSON_GetArraySize(js), 3);
    const cJSON *s1 = cJSON_GetArrayItem(js, 1);
    assert_int_equal(cJSON_GetArraySize(s1), 4);
    assert_true(cJSON_GetArrayItem(s1, 0)->valuedouble == 0.5);
    assert_true(cJSON_GetArrayItem(s1, 2)->valuedouble == 7 &&
                cJSON_GetArrayItem(s1, 3)->valuedouble == IIR_SITE_NEW);
    const cJSON *je = cJSON_GetObjectItemCaseSensitive(o, "edges");
    assert_int_equal(cJSON_GetArraySize(je), 3);
    assert_true(cJSON_GetArrayItem(cJSON_GetArrayItem(je, 1), 1)->valuedouble == 2);
    const cJSON *jc = cJSON_GetObjectItemCaseSensitive(o, "cells");
    assert_int_equal(cJSON_GetArraySize(jc), 3);
    assert_int_equal(cJSON_GetArraySize(cJSON_GetArrayItem(jc, 0)), 3);
    assert_int_equal(cJSON_GetArraySize(cJSON_GetArrayItem(jc, 1)), 2);
    const cJSON *last = cJSON_GetArrayItem(cJSON_GetArrayItem(jc, 2), 2);
    assert_true(cJSON_GetArrayItem(last, 0)->valuedouble == 0.12346); /* rounded to 1e-5 */
    const cJSON *jr = cJSON_GetObjectItemCaseSensitive(o, "removed");
    assert_int_equal(cJSON_GetArraySize(jr), 1);
    assert_true(cJSON_GetArrayItem(cJSON_GetArrayItem(jr, 0), 0)->valuedouble == 1.5);
    cJSON_Delete(o);
}

/* ======================== fuzz ======================== */

static const char *const SEEDS[] = {
    "{\"type\":\"hello\",\"protocol\":1,\"token\":\"abc\",\"client\":\"test\",\"seq\":0}",
    "{\"type\":\"light\",\"seq\":1,\"position\":[0,1.9,0],\"target\":[0,0,0],\"cone_angle\":45,"
    "\"intensity\":[4,2.5,1]}",
    "{\"type\":\"light\",\"direction\":[0,-1,0.2],\"intensity\":3}",
    "{\"type\":\"camera\",\"position\":[0,1,3.9],\"target\":[0,1,0],\"up\":[0,1,0],\"fov\":39.3}",
    "{\"type\":\"params\",\"method\":\"iir\",\"vpls\":256,\"kmin\":4,\"kmax\":8,\"weights\":"
    "\"voronoi\",\"visibility\":\"rays\",\"interleave\":4,\"clamp\":100,\"sm_res\":128,"
    "\"bounces\":2,\"spp\":1,\"width\":512,\"height\":384,\"quality\":80,\"exposure\":0,"
    "\"refine\":true,\"refine_passes\":64,\"domain\":true,\"seed\":1}",
    "{\"type\":\"scene\",\"name\":\"cornell_box\",\"seq\":5}",
    "{\"type\":\"pick\",\"x\":100.5,\"y\":20}",
    "{\"type\":\"snapshot\",\"format\":\"exr\"}",
    "{\"type\":\"record\",\"action\":\"start\",\"fps\":60}",
};

static const char JSONISH[] = "{}[]\",:0123456789.-+eE \\truefalsnl\xc3\xa9\xff\x00";

/* One random edit of buf (len bytes, capacity cap). */
static size_t mutate(iir_rng *rng, char *buf, size_t len, size_t cap)
{
    uint32_t op = iir_rng_u32(rng) % 6, at = len ? iir_rng_u32(rng) % (uint32_t)len : 0;
    char ch = (iir_rng_u32(rng) & 1) ? JSONISH[iir_rng_u32(rng) % (sizeof JSONISH - 1)]
                                     : (char)(iir_rng_u32(rng) & 0xFF);
    switch (op) {
    case 0:
        if (len) buf[at] = ch;
        return len; /* replace */
    case 1:         /* insert */
        if (len + 1 >= cap) return len;
        memmove(buf + at + 1, buf + at, len - at);
        buf[at] = ch;
        return len + 1;
    case 2:
        if (len) memmove(buf + at, buf + at + 1, len - at - 1);
        return len ? len - 1 : 0;
    case 3:
        return at; /* truncate */
    case 4: {      /* duplicate a span */
        size_t n = 1 + iir_rng_u32(rng) % 16;
        if (at + n > len || len + n >= cap) return len;
        memmove(buf + at + n, buf + at, len - at);
        return len + n;
    }
    default: { /* swap two bytes */
        uint32_t b = len ? iir_rng_u32(rng) % (uint32_t)len : 0;
        char t = buf[at];
        buf[at] = buf[b];
        buf[b] = t;
        return len;
    }
    }
}

/* A shaped area light (a 32-gon) in `state`: its `shape` is sent, every corner the same float; a
 * rectangle sends none; a client's `light` message cannot carry one. `save`'s sidecar writes the
 * shape so that the scene it makes loads the same light (pose, size, shape bit for bit). */
static void test_shaped_light_sent_and_saved(void **state)
{
    (void)state;
    iir_light L = {.type = IIR_LIGHT_AREA, .name = "disc"};
    L.position = iir_v3(0.1f, 1.9f, -0.2f);
    L.direction = iir_v3(0.f, -1.f, 0.f);
    L.up = iir_v3(0.f, 0.f, 1.f);
    L.size = iir_v2(0.5f, 0.3f);
    L.intensity = iir_v3(5.f, 4.f, 3.f);
    iir_test_disc_shape(&L.shape, 32);
    iir_camera C = cam();
    iird_settings s = iird_settings_default();
    iird_state_view v = {"builtin", &L, &C, &s, 1, false, NULL, NULL, NULL, 0};
    cJSON *o = reply_ok(iird_json_state(&v, 1), "state");
    const cJSON *shape =
        cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(o, "light"), "shape");
    assert_true(cJSON_IsArray(shape) && cJSON_GetArraySize(shape) == 32);
    for (int t = 0; t < 32; t++)
        for (int k = 0; k < 3; k++) {
            const cJSON *p = cJSON_GetArrayItem(cJSON_GetArrayItem(shape, t), k);
            assert_true(cJSON_IsArray(p) && cJSON_GetArraySize(p) == 2);
            assert_true((float)cJSON_GetArrayItem(p, 0)->valuedouble == L.shape.tri[t][k].x);
            assert_true((float)cJSON_GetArrayItem(p, 1)->valuedouble == L.shape.tri[t][k].y);
        }
    cJSON_Delete(o);
    iir_light rect = L;
    memset(&rect.shape, 0, sizeof rect.shape);
    v.light = &rect;
    o = reply_ok(iird_json_state(&v, 1), "state");
    assert_null(
        cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(o, "light"), "shape"));
    cJSON_Delete(o);
    expect("{\"type\":\"light\",\"shape\":[[[0,0],[0.5,0],[0,0.5]]]}", IIRD_E_UNKNOWN_FIELD,
           "light.shape");

    /* save: the sidecar, loaded as a scene based on the built-in box */
    iird_sidecar_view sv = {"builtin", &C, 1.f, &L, 1};
    char *text = iird_sidecar_text(&sv);
    assert_non_null(text);
    assert_non_null(strstr(text, "\"shape\""));
    const char *dir = iir_test_tmpdir("protocol-saved-disc");
    const char *path = iir_test_write_file(dir, "saved.scene.json", text);
    free(text);
    iir_scene *scene = NULL;
    iir_error err = {0};
    if (iir_scene_load(path, &scene, &err) != IIR_OK) fail_msg("%s", err.msg);
    assert_int_equal(scene->num_lights, 1);
    const iir_light *back = &scene->lights[0];
    assert_string_equal(back->name, "disc");
    assert_true(back->size.x == L.size.x && back->size.y == L.size.y);
    assert_near3(back->position, L.position, 0.f);
    assert_int_equal(back->shape.num_triangles, 32);
    assert_memory_equal(&back->shape, &L.shape, sizeof L.shape);
    iir_scene_destroy(scene);
}

static void test_fuzz(void **state)
{
    (void)state;
    iir_rng rng = iir_rng_make(20240607, 1);
    char buf[1024];
    int parsed = 0, codes[IIRD_E_COUNT] = {0};
    for (int it = 0; it < 5000; it++) {
        const char *seed = SEEDS[iir_rng_u32(&rng) % (sizeof SEEDS / sizeof SEEDS[0])];
        size_t len = strlen(seed);
        memcpy(buf, seed, len);
        int edits = 1 + (int)(iir_rng_u32(&rng) % 4);
        for (int k = 0; k < edits; k++) len = mutate(&rng, buf, len, sizeof buf);
        /* parse from a heap copy of exactly len bytes so ASan sees any over-read */
        char *copy = malloc(len ? len : 1);
        memcpy(copy, buf, len);
        iird_msg m;
        iird_proto_error e;
        memset(&e, 0, sizeof e);
        bool ok = iird_parse_message(copy, len, &LIM, &m, &e);
        free(copy);
        if (ok) {
            parsed++;
            iir_light L = spot();
            iir_camera C = cam();
            iird_settings s = iird_settings_default();
            if (m.type == IIRD_MSG_LIGHT) (void)iird_apply_light(&m.u.light, &L, &e);
            if (m.type == IIRD_MSG_CAMERA) (void)iird_apply_camera(&m.u.camera, &C, &e);
            if (m.type == IIRD_MSG_PARAMS) (void)iird_apply_params(&m.u.params, &LIM, &s, &e);
            continue;
        }
        assert_true((unsigned)e.code < IIRD_E_COUNT);
        codes[e.code]++;
        assert_true(strlen(e.message) > 0);
        assert_true(e.seq == IIRD_NO_SEQ || (e.seq >= 0 && e.seq <= 4294967294LL));
        cJSON *o = reply_ok(iird_json_error(&e), "error");
        cJSON_Delete(o);
    }
    /* the mutations reach both outcomes and several codes */
    assert_true(parsed > 100 && parsed < 4900);
    assert_true(codes[IIRD_E_BAD_JSON] > 100);
    assert_true(codes[IIRD_E_UNKNOWN_FIELD] + codes[IIRD_E_UNKNOWN_TYPE] > 10);
    assert_true(codes[IIRD_E_BAD_TYPE] + codes[IIRD_E_OUT_OF_RANGE] > 10);
}

/* A \u0000 escape in any string (issue 15): cJSON's NUL would cut the string short, so
 * "cornell_box\u0000/../x" must not read as cornell_box nor "iir\u0000xyz" as iir. */
static void test_embedded_nul(void **state)
{
    (void)state;
    expect("{\"type\":\"scene\",\"name\":\"cornell_box\\u0000/../../etc\"}", IIRD_E_OUT_OF_RANGE,
           "scene.name");
    expect("{\"type\":\"scene\",\"name\":\"\\u0000\"}", IIRD_E_OUT_OF_RANGE, "scene.name");
    expect("{\"type\":\"params\",\"method\":\"iir\\u0000xyz\"}", IIRD_E_OUT_OF_RANGE,
           "params.method");
    expect("{\"type\":\"params\",\"method\":\"iir\\u0000\"}", IIRD_E_OUT_OF_RANGE, "params.method");
    expect("{\"type\":\"hello\",\"client\":\"a\\u0000b\"}", IIRD_E_OUT_OF_RANGE, "hello.client");
    expect("{\"type\":\"hello\",\"token\":\"t\\u0000\"}", IIRD_E_OUT_OF_RANGE, "hello.token");
    expect("{\"type\":\"snapshot\",\"format\":\"png\\u0000\"}", IIRD_E_OUT_OF_RANGE,
           "snapshot.format");
    expect("{\"type\":\"light\\u0000\"}", IIRD_E_OUT_OF_RANGE, "type");
    /* a NUL in a member's name is not that member */
    expect("{\"type\":\"scene\",\"name\\u0000\":\"cornell_box\"}", IIRD_E_UNKNOWN_FIELD,
           "scene.name");
    /* an escaped backslash before u0000 is no NUL; a NUL escape outside a string is bad JSON */
    iird_msg m = parse_ok("{\"type\":\"hello\",\"client\":\"a\\\\u0000b\"}");
    assert_string_equal(m.u.hello.client, "a\\u0000b");
    m = parse_ok("{\"type\":\"hello\",\"client\":\"\\u0001\\u00e9\"}");
    assert_string_equal(m.u.hello.client, "\x01\xc3\xa9");
    expect("{\"type\":\"hello\"}\\u0000", IIRD_E_BAD_JSON, "");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_envelope),
        cmocka_unit_test(test_size_and_nesting),
        cmocka_unit_test(test_type_and_seq),
        cmocka_unit_test(test_unknown_and_duplicate),
        cmocka_unit_test(test_hello),
        cmocka_unit_test(test_scene_pick_snapshot_record),
        cmocka_unit_test(test_light_parse),
        cmocka_unit_test(test_light_apply),
        cmocka_unit_test(test_camera),
        cmocka_unit_test(test_params_parse),
        cmocka_unit_test(test_params_apply),
        cmocka_unit_test(test_recording_round_trip),
        cmocka_unit_test(test_recording_lights),
        cmocka_unit_test(test_frame_header),
        cmocka_unit_test(test_json_replies),
        cmocka_unit_test(test_json_domain),
        cmocka_unit_test(test_shaped_light_sent_and_saved),
        cmocka_unit_test(test_fuzz),
        cmocka_unit_test(test_embedded_nul),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
