/* testutil.c -- scratch directories, file writers and method shortcuts for the unit tests. */
#include "testutil.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

const char *iir_test_tmpdir(const char *test_name)
{
    static char path[1024];
    const char *base = getenv("IIR_TEST_TMP");
    if (!base || !*base) base = "/tmp/iir-test";
    mkdir(base, 0755);
    snprintf(path, sizeof path, "%s/%s-%d", base, test_name, (int)getpid());
    mkdir(path, 0755);
    return path;
}

const char *iir_test_write_file(const char *dir, const char *name, const char *text)
{
    static char path[1200]; /* dir (iir_test_tmpdir's, under 1024) and a name */
    if (snprintf(path, sizeof path, "%s/%s", dir, name) >= (int)sizeof path) return NULL;
    FILE *f = fopen(path, "wb");
    if (!f) return NULL;
    fwrite(text, 1, strlen(text), f);
    fclose(f);
    return path;
}

FILE *iir_test_open_obj(const char *dir, const char *name, const char *mtl_text)
{
    char file[256], path[1200];
    snprintf(file, sizeof file, "%s.mtl", name);
    iir_test_write_file(dir, file, mtl_text);
    snprintf(path, sizeof path, "%s/%s.obj", dir, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "mtllib %s.mtl\n", name);
    return f;
}

void iir_test_write_quad(FILE *f, const char *mtl, iir_vec3 c, iir_vec3 a, iir_vec3 b)
{
    iir_vec3 v[4] = {iir_sub(iir_sub(c, a), b), iir_sub(iir_add(c, a), b),
                     iir_add(iir_add(c, a), b), iir_add(iir_sub(c, a), b)};
    fprintf(f, "usemtl %s\n", mtl);
    for (int i = 0; i < 4; i++) fprintf(f, "v %.9g %.9g %.9g\n", v[i].x, v[i].y, v[i].z);
    fprintf(f, "f -4 -3 -2 -1\n");
}

void iir_test_write_disc(FILE *f, const char *mtl, iir_vec3 c, iir_vec3 a, iir_vec3 b, int n)
{
    fprintf(f, "usemtl %s\nv %.9g %.9g %.9g\n", mtl, c.x, c.y, c.z);
    for (int k = 0; k < n; k++) {
        double t = 2 * M_PI * k / n;
        iir_vec3 p = iir_add(c, iir_add(iir_scale(a, (float)cos(t)), iir_scale(b, (float)sin(t))));
        fprintf(f, "v %.9g %.9g %.9g\n", p.x, p.y, p.z);
    }
    for (int k = 0; k < n; k++) fprintf(f, "f %d %d %d\n", -(n + 1), -(n - k), -(n - (k + 1) % n));
}

void iir_test_disc_shape(iir_area_shape *s, int n)
{
    memset(s, 0, sizeof *s);
    s->num_triangles = (uint32_t)n;
    for (int k = 0; k < n; k++) {
        double t0 = 2 * M_PI * k / n, t1 = 2 * M_PI * (k + 1) / n;
        s->tri[k][0] = iir_v2(0.f, 0.f);
        s->tri[k][1] = iir_v2((float)(0.5 * cos(t0)), (float)(0.5 * sin(t0)));
        s->tri[k][2] = iir_v2((float)(0.5 * cos(t1)), (float)(0.5 * sin(t1)));
    }
}

iir_status iir_test_load_obj(const char *dir, const char *name, iir_scene **scene, iir_rt **rt,
                             iir_error *err)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s.obj", dir, name);
    return iir_scene_open(path, NULL, scene, rt, err);
}

iir_test_cornell iir_test_load(const char *dir, const char *name)
{
    iir_test_cornell l = {0};
    iir_error err = {0};
    if (iir_test_load_obj(dir, name, &l.scene, &l.rt, &err) != IIR_OK) fail_msg("%s", err.msg);
    return l;
}

void iir_test_unload(iir_test_cornell *l)
{
    iir_rt_destroy(l->rt);
    iir_scene_destroy(l->scene);
}

int iir_test_cornell_setup(void **state)
{
    static iir_test_cornell f;
    iir_error err = {0};
    if (iir_scene_open("builtin", NULL, &f.scene, &f.rt, &err) != IIR_OK) return -1;
    *state = &f;
    return 0;
}

int iir_test_cornell_teardown(void **state)
{
    iir_test_cornell *f = *state;
    iir_rt_destroy(f->rt);
    iir_scene_destroy(f->scene);
    return 0;
}

iir_method *iir_test_method(const iir_test_cornell *f, const char *name, const iir_params *p)
{
    iir_method *m = NULL;
    iir_error err = {0};
    if (iir_method_create(name, f->scene, f->rt, p, &m, &err) != IIR_OK) fail_msg("%s", err.msg);
    return m;
}

void iir_test_render(iir_method *m, const iir_view *v, iir_image *img, iir_frame_stats *fs)
{
    iir_error err = {0};
    if (iir_method_render(m, v, img, fs, &err) != IIR_OK) fail_msg("%s", err.msg);
}

void iir_test_set(iir_params *p, const char *name, double v)
{
    iir_error err = {0};
    if (iir_method_param_set(p, name, v, &err) != IIR_OK) fail_msg("%s", err.msg);
}

double iir_test_get(const iir_params *p, const char *name)
{
    const iir_param *row = iir_method_any_param(name);
    if (!row) fail_msg("no parameter %s", name);
    return iir_method_param_value(row, p);
}

bool iir_test_smooth_pixel(const iir_gbuffer *gb, int x, int y)
{
    if (x == 0 || y == 0 || x == gb->width - 1 || y == gb->height - 1) return false;
    size_t c = (size_t)y * gb->width + x;
    if (gb->prim[c] == IIR_NO_HIT) return false;
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
            size_t k = (size_t)(y + dy) * gb->width + (x + dx);
            if (gb->prim[k] == IIR_NO_HIT || iir_dot(gb->normal[k], gb->normal[c]) < 0.999f)
                return false;
        }
    return true;
}

double iir_test_gltf_brdf(double base, double metallic, double roughness, const double wo[3],
                          const double wi[3])
{
    double nl = wi[1], nv = wo[1];
    if (nl <= 0 || nv <= 0) return 0;
    double h[3] = {wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]};
    double hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    for (int k = 0; k < 3; k++) h[k] /= hl;
    double nh = h[1], vh = fabs(wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2]);
    double a = roughness * roughness, a2 = a * a;
    double dd = nh * nh * (a2 - 1) + 1;
    double D = a2 / (M_PI * dd * dd); /* (nh > 0 always: h between two upper directions) */
    double V = 0.5 / (nl * sqrt(nv * nv * (1 - a2) + a2) + nv * sqrt(nl * nl * (1 - a2) + a2));
    double s = pow(1 - vh, 5);
    double specular = V * D;
    /* dielectric_brdf = mix(diffuse, specular, F(0.04)); metal_brdf = specular F(base) */
    double Fd = 0.04 + (1 - 0.04) * s, Fm = base + (1 - base) * s;
    double dielectric = (1 - Fd) * base / M_PI + Fd * specular;
    double metal = Fm * specular;
    return (1 - metallic) * dielectric + metallic * metal;
}

void iir_test_corner_obj(const char *dir, const char *mtl_text, const char *floor, const char *back,
                         const char *left)
{
    FILE *f = iir_test_open_obj(dir, "corner", mtl_text);
    iir_test_write_quad(f, floor, iir_v3(0, 0, 0), iir_v3(0, 0, 2), iir_v3(2, 0, 0));
    iir_test_write_quad(f, back, iir_v3(0, 2, -2), iir_v3(2, 0, 0), iir_v3(0, 2, 0));
    iir_test_write_quad(f, left, iir_v3(-2, 2, 0), iir_v3(0, 2, 0), iir_v3(0, 0, 2));
    fclose(f);
}

iir_test_cornell iir_test_brass_corner(void)
{
    const char *dir = iir_test_tmpdir("lineage-brass-corner");
    iir_test_corner_obj(dir,
                        "newmtl brass\nKd 0.9 0.7 0.45\nPm 1\nPr 0.4\nnewmtl grey\nKd 0.7 0.7 "
                        "0.7\nnewmtl red\nKd 0.7 0.2 0.2\n",
                        "brass", "grey", "red");
    iir_test_write_file(dir, "corner.scene.json",
                        "{\"camera\": {\"position\": [3, 3.5, 6], \"target\": [-0.5, 0.8, -0.5],"
                        " \"fov_y\": 50}, \"lights\": [{\"type\": \"spot\", \"name\": \"spot\","
                        " \"position\": [1.5, 2.5, 1.5], \"direction\": [-0.3, -1, -0.5],"
                        " \"intensity\": [6, 6, 6], \"cone_angle\": 40}]}");
    return iir_test_load(dir, "corner");
}
