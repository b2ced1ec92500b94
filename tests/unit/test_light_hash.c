/* test_light_hash.c -- a light and a material own their content key (iir_light_hash,
 * iir_material_hash): changing any one field that changes an image, once, gives a new key (an area
 * light's size, shape and radiance image among them: iird bench's reference cache once reused a
 * reference across a lamp's resize); the name, which changes no image, keeps it; the key is the
 * same for equal lights whatever their padding bytes hold. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>
#include <cmocka.h>

#include "iir/hash.h"
#include "iir/light.h"
#include "iir/scene.h"

static iir_light area_light(void)
{
    iir_light l;
    memset(&l, 0, sizeof l);
    l.type = IIR_LIGHT_AREA;
    strcpy(l.name, "lamp");
    l.position = iir_v3(0.f, 1.9f, 0.f);
    l.direction = iir_v3(0.f, -1.f, 0.f);
    l.up = iir_v3(0.f, 0.f, 1.f);
    l.cone_angle = 1.f, l.smooth = 0.1f, l.inner_angle = 0.5f, l.radius = 2.f;
    l.size = iir_v2(0.5f, 0.4f);
    l.intensity = iir_v3(10.f, 9.f, 8.f);
    return l;
}

static uint64_t key(const iir_light *l)
{
    return iir_light_hash(IIR_HASH_BASIS, l);
}

/* One field changed at a time, each against the base light. */
static void test_every_light_field(void **state)
{
    (void)state;
    static iir_vec3 texels[4] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
    static iir_emission_map map = {2, 2, texels, {0.5f, 0.5f, 0.5f}, "/maps/m.png"};
    const iir_light base = area_light();
    const uint64_t k0 = key(&base);
    iir_light l[16];
    int n = 0;
    for (int i = 0; i < 16; i++) l[i] = base;
    l[n++].type = IIR_LIGHT_SPOT;
    l[n++].position.x += 0.01f;
    l[n++].direction.z = 0.1f;
    l[n++].up.x = 1.f;
    l[n++].cone_angle = 0.9f;
    l[n++].smooth = 0.2f;
    l[n++].profile = IIR_SPOT_GLTF;
    l[n++].inner_angle = 0.4f;
    l[n++].radius = 3.f;
    l[n++].size.x = 0.6f;
    l[n].shape.num_triangles = 1;
    l[n++].shape.tri[0][1] = iir_v2(0.5f, 0.f);
    l[n++].map = &map;
    l[n++].intensity.y = 9.5f;
    for (int i = 0; i < n; i++) {
        print_message("field %d: %016llx against %016llx\n", i, (unsigned long long)key(&l[i]),
                      (unsigned long long)k0);
        assert_true(key(&l[i]) != k0);
    }
    /* the radiance image by its texels, not its address or path */
    iir_vec3 texels2[4];
    memcpy(texels2, texels, sizeof texels);
    iir_emission_map map2 = map;
    map2.texels = texels2;
    strcpy(map2.path, "/elsewhere/m.png");
    iir_light a = base, b = base;
    a.map = &map, b.map = &map2;
    assert_true(key(&a) == key(&b));
    texels2[3].y = 0.5f;
    assert_true(key(&a) != key(&b));
    /* the name changes no image */
    iir_light named = base;
    strcpy(named.name, "other");
    assert_true(key(&named) == k0);
}

/* Equal lights built over different garbage (padding, unused shape slots, the name's tail). */
static void test_padding_does_not_count(void **state)
{
    (void)state;
    iir_light a, b;
    memset(&a, 0x00, sizeof a);
    memset(&b, 0xA5, sizeof b);
    const iir_light base = area_light();
    a.type = b.type = base.type;
    a.position = b.position = base.position;
    a.direction = b.direction = base.direction;
    a.up = b.up = base.up;
    a.cone_angle = b.cone_angle = base.cone_angle;
    a.smooth = b.smooth = base.smooth;
    a.profile = b.profile = base.profile;
    a.inner_angle = b.inner_angle = base.inner_angle;
    a.radius = b.radius = base.radius;
    a.size = b.size = base.size;
    a.shape.num_triangles = b.shape.num_triangles = 0;
    a.map = b.map = NULL;
    a.intensity = b.intensity = base.intensity;
    assert_true(key(&a) == key(&b));
}

static void test_every_material_field(void **state)
{
    (void)state;
    iir_material base;
    memset(&base, 0, sizeof base);
    strcpy(base.name, "white");
    base.albedo = iir_v3(0.7f, 0.7f, 0.7f);
    const uint64_t k0 = iir_material_hash(IIR_HASH_BASIS, &base);
    iir_material m[5];
    for (int i = 0; i < 5; i++) m[i] = base;
    m[0].albedo.z = 0.6f;
    m[1].emission.x = 1.f;
    m[2].kind = IIR_MATERIAL_MIRROR;
    m[3].specular.y = 0.5f;
    m[4].ior = 1.5f;
    for (int i = 0; i < 5; i++) assert_true(iir_material_hash(IIR_HASH_BASIS, &m[i]) != k0);
    iir_material named = base;
    strcpy(named.name, "paint");
    assert_true(iir_material_hash(IIR_HASH_BASIS, &named) == k0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_light_field),
        cmocka_unit_test(test_padding_does_not_count),
        cmocka_unit_test(test_every_material_field),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
