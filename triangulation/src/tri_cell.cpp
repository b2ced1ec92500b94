// tri_cell.cpp -- one Voronoi cell clipped to the disk, computed exactly from its site and Delaunay
// neighbours: half-plane clipping, then the walk that replaces the parts outside the circle by
// arcs, and what a summary reads from a cell; not how sites or neighbours are found
// (tri_domain.cpp).
//
// The cell is first built as a convex polygon: a square of half-side 2R around the disk, cut by the
// bisector half-plane of every neighbour (taken in the caller's order, ascending id, so the result
// does not depend on CGAL's storage order). Walking that polygon counter-clockwise, each edge is
// cut at the circle: parts inside the disk are straight sides of the clipped cell, and each run of
// parts outside is replaced by the arc from where the walk leaves the disk to where it re-enters.
// The arc's angle is the signed angle the outside run sweeps around the origin, which stays exact
// even when the run is tiny or wraps almost a full turn.
#include "tri_cell.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace iirdisk
{
namespace
{

constexpr double kPi = 3.14159265358979323846264338327950288;
constexpr double kTwoPi = 2 * kPi;

Vec2 operator-(Vec2 a, Vec2 b)
{
    return {a.x - b.x, a.y - b.y};
}
double dot(Vec2 a, Vec2 b)
{
    return a.x * b.x + a.y * b.y;
}
double cross(Vec2 a, Vec2 b)
{
    return a.x * b.y - a.y * b.x;
}
Vec2 lerp(Vec2 a, Vec2 b, double t)
{
    return {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)};
}

// Signed angle from direction a to direction b around the origin, in (-pi, pi].
double angle_between(Vec2 a, Vec2 b)
{
    return std::atan2(cross(a, b), dot(a, b));
}

// ---- step 1: the cell as a convex polygon ----

// Returned by clip_halfplane when no vertex is cut off.
constexpr size_t kUnchanged = SIZE_MAX;

// Keeps the part of the convex counter-clockwise polygon in[0..n) where (x - m).d <= 0
// (Sutherland-Hodgman): writes it to out (room for 2n vertices) and returns its vertex count, or
// kUnchanged, writing nothing, when the polygon is already inside. Each vertex's side is evaluated
// once into g[0..n) and shared by the two edges that meet there.
size_t clip_halfplane(const Vec2 *in, size_t n, Vec2 m, Vec2 d, double *g, Vec2 *out)
{
    bool cut = false;
    for (size_t k = 0; k < n; k++) {
        g[k] = dot(in[k] - m, d);
        cut |= !(g[k] <= 0);
    }
    if (!cut) return kUnchanged;
    size_t w = 0;
    for (size_t k = 0; k < n; k++) {
        const size_t next = k + 1 == n ? 0 : k + 1;
        const double ga = g[k], gb = g[next];
        if (ga <= 0) out[w++] = in[k];
        if ((ga < 0 && gb > 0) || (ga > 0 && gb < 0))
            out[w++] = lerp(in[k], in[next], ga / (ga - gb));
    }
    return w;
}

// The cell as a polygon in scratch.poly[0..returned count).
size_t cell_polygon_in_square(const Site &self, const Site *nbrs, size_t n, double R,
                              Cell_scratch &s)
{
    const double h = 2 * R;
    if (s.poly.size() < 4) s.poly.resize(4);
    s.poly[0] = {-h, -h}, s.poly[1] = {h, -h}, s.poly[2] = {h, h}, s.poly[3] = {-h, h};
    size_t np = 4;
    for (size_t k = 0; k < n; k++) {
        const Site &o = nbrs[k];
        Vec2 m = {0.5 * (self.p.x + o.p.x), 0.5 * (self.p.y + o.p.y)};
        Vec2 d = {o.p.x - self.p.x, o.p.y - self.p.y};
        if (s.tmp.size() < 2 * np) s.tmp.resize(2 * np);
        if (s.side.size() < np) s.side.resize(np);
        size_t w = clip_halfplane(s.poly.data(), np, m, d, s.side.data(), s.tmp.data());
        if (w == kUnchanged) continue;
        s.poly.swap(s.tmp);
        np = w;
    }
    return np;
}

// ---- step 2: the polygon's boundary cut at the circle ----

// Cuts edge a->b at the circle into out (room for 3 steps); returns the number of steps. Whether an
// end is inside is decided once per vertex, so neighbouring edges always agree about their shared
// vertex.
size_t split_edge(Vec2 a, Vec2 b, bool ina, bool inb, double R, Step *out)
{
    if (ina && inb) {
        out[0] = {a, b, true};
        return 1;
    }
    Vec2 d = b - a;
    double A = dot(d, d), B = dot(a, d), C = dot(a, a) - R * R;
    if (A == 0) return 0;
    double disc = B * B - A * C, sq = disc > 0 ? std::sqrt(disc) : 0.0;
    double t0 = (-B - sq) / A, t1 = (-B + sq) / A;
    if (ina) {
        Vec2 p = lerp(a, b, std::clamp(t1, 0.0, 1.0));
        out[0] = {a, p, true};
        out[1] = {p, b, false};
        return 2;
    }
    if (inb) {
        Vec2 p = lerp(a, b, std::clamp(t0, 0.0, 1.0));
        out[0] = {a, p, false};
        out[1] = {p, b, true};
        return 2;
    }
    if (disc > 0 && t0 > 0 && t1 < 1) {
        Vec2 p0 = lerp(a, b, t0), p1 = lerp(a, b, t1);
        out[0] = {a, p0, false};
        out[1] = {p0, p1, true};
        out[2] = {p1, b, false};
        return 3;
    }
    out[0] = {a, b, false};
    return 1;
}

// The boundary of poly[0..n) cut at the circle, in scratch.steps[0..returned count).
size_t split_at_circle(const Vec2 *poly, size_t n, double R, Cell_scratch &s)
{
    if (s.inside.size() < n) s.inside.resize(n);
    if (s.steps.size() < 3 * n) s.steps.resize(3 * n);
    for (size_t k = 0; k < n; k++) s.inside[k] = dot(poly[k], poly[k]) <= R * R;
    size_t w = 0;
    for (size_t k = 0; k < n; k++) {
        size_t next = k + 1 == n ? 0 : k + 1;
        w += split_edge(poly[k], poly[next], s.inside[k], s.inside[next], R, &s.steps[w]);
    }
    return w;
}

// ---- step 3: runs outside the disk become arcs ----

bool is_side(const Step &s)
{
    return s.inside && (s.a.x != s.b.x || s.a.y != s.b.y);
}

Piece full_circle(double R)
{
    return {{R, 0}, {R, 0}, true, kTwoPi};
}

void join_into_ring(const Step *steps, size_t n, double R, std::vector<Piece> &ring)
{
    ring.clear();
    size_t first = std::find_if(steps, steps + n, is_side) - steps;
    if (first == n) {
        // No straight side: the polygon holds the whole disk (outside runs sweep a full turn) or
        // misses it (they sweep nothing).
        double total = 0;
        for (size_t k = 0; k < n; k++) total += angle_between(steps[k].a, steps[k].b);
        if (total > kPi) ring.push_back(full_circle(R));
        return;
    }
    double swept = 0;
    bool outside = false;
    Vec2 last_end{};
    for (size_t j = 0; j <= n; j++) {
        const Step &s = steps[(first + j) % n];
        if (!is_side(s)) {
            if (!s.inside) {
                swept += angle_between(s.a, s.b);
                outside = true;
            }
            continue;
        }
        if (outside && swept > 0) ring.push_back({last_end, s.a, true, std::min(swept, kTwoPi)});
        if (j == n) break;
        ring.push_back({s.a, s.b, false, 0.0});
        last_end = s.b;
        swept = 0;
        outside = false;
    }
}

} // namespace

// ---- the cell ----

const Cell &clip_cell(const Site &self, const Site *nbrs, size_t n, double R, Cell_scratch &scratch)
{
    size_t np = cell_polygon_in_square(self, nbrs, n, R, scratch);
    size_t ns = split_at_circle(scratch.poly.data(), np, R, scratch);
    Cell &c = scratch.cell;
    c.site = self.p;
    c.R = R;
    join_into_ring(scratch.steps.data(), ns, R, c.ring);
    return c;
}

double cell_area(const Cell &c)
{
    double twice = 0;
    for (const Piece &p : c.ring) twice += p.arc ? c.R * c.R * p.sweep : cross(p.a, p.b);
    return 0.5 * twice;
}

void cell_polygon(const Cell &c, std::vector<Vec2> &out)
{
    out.clear();
    for (const Piece &p : c.ring) {
        out.push_back(p.a);
        if (!p.arc) continue;
        int m = std::max(1, (int)std::ceil(p.sweep * IIR_TRI_ARC_SEGMENTS / kTwoPi - 1e-9));
        double theta = std::atan2(p.a.y, p.a.x);
        for (int k = 1; k < m; k++) {
            double phi = theta + p.sweep * k / m;
            out.push_back({c.R * std::cos(phi), c.R * std::sin(phi)});
        }
    }
}

void far_candidates(const Cell &c, std::vector<Candidate> &out)
{
    const double s = std::hypot(c.site.x, c.site.y);
    Vec2 opposite = {0, 0};
    if (s > 0) opposite = {-c.R * c.site.x / s, -c.R * c.site.y / s};
    uint32_t k = 0;
    auto add = [&](Vec2 p) {
        out.push_back({p, std::hypot(p.x - c.site.x, p.y - c.site.y), Ring_key{k++}});
    };
    for (const Piece &p : c.ring) {
        add(p.a);
        if (!p.arc || s == 0) continue; // a site at the origin: every arc point is equally far
        double rel = angle_between(p.a, opposite);
        if (rel < 0) rel += kTwoPi;
        if (rel <= p.sweep) add(opposite);
    }
}

bool shortest_incident(const Site &self, const Site *nbrs, size_t n, iirtri::Edge_key &out)
{
    for (size_t k = 0; k < n; k++) {
        const Site &young = self.id > nbrs[k].id ? self : nbrs[k];
        const Site &old = self.id > nbrs[k].id ? nbrs[k] : self;
        iirtri::Edge_key e = {dist2(young.p, old.p), young.id, old.id};
        if (k == 0 || iirtri::shorter(e, out)) out = e;
    }
    return n > 0;
}

} // namespace iirdisk
