// tri_cell.cpp -- one Voronoi cell clipped to the disk, computed exactly from its site and Delaunay
// neighbours: half-plane clipping, then the walk that replaces the parts outside the circle by
// arcs; not how sites or neighbours are found (tri_query.cpp).
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

namespace iirtri
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

// Keeps the part of the convex counter-clockwise polygon where (x - m).d <= 0 (Sutherland-Hodgman).
void clip_halfplane(std::vector<Vec2> &poly, Vec2 m, Vec2 d, std::vector<Vec2> &tmp)
{
    tmp.clear();
    const size_t n = poly.size();
    for (size_t k = 0; k < n; k++) {
        Vec2 a = poly[k], b = poly[(k + 1) % n];
        double ga = dot(a - m, d), gb = dot(b - m, d);
        if (ga <= 0) tmp.push_back(a);
        if ((ga < 0 && gb > 0) || (ga > 0 && gb < 0)) tmp.push_back(lerp(a, b, ga / (ga - gb)));
    }
    poly.swap(tmp);
}

std::vector<Vec2> cell_polygon_in_square(const Site &self, const std::vector<Site> &nbrs, double R)
{
    const double h = 2 * R;
    std::vector<Vec2> poly = {{-h, -h}, {h, -h}, {h, h}, {-h, h}}, tmp;
    for (const Site &o : nbrs) {
        Vec2 m = {0.5 * (self.x + o.x), 0.5 * (self.y + o.y)};
        Vec2 d = {o.x - self.x, o.y - self.y};
        clip_halfplane(poly, m, d, tmp);
    }
    return poly;
}

// ---- step 2: the polygon's boundary cut at the circle ----

// A straight part of the polygon boundary, either inside the disk or outside it.
struct Step {
    Vec2 a, b;
    bool inside;
};

// Cuts edge a->b at the circle. Whether an end is inside is decided once per vertex, so
// neighbouring edges always agree about their shared vertex.
void split_edge(Vec2 a, Vec2 b, bool ina, bool inb, double R, std::vector<Step> &out)
{
    if (ina && inb) {
        out.push_back({a, b, true});
        return;
    }
    Vec2 d = b - a;
    double A = dot(d, d), B = dot(a, d), C = dot(a, a) - R * R;
    if (A == 0) return;
    double disc = B * B - A * C, sq = disc > 0 ? std::sqrt(disc) : 0.0;
    double t0 = (-B - sq) / A, t1 = (-B + sq) / A;
    if (ina) {
        Vec2 p = lerp(a, b, std::clamp(t1, 0.0, 1.0));
        out.push_back({a, p, true});
        out.push_back({p, b, false});
    } else if (inb) {
        Vec2 p = lerp(a, b, std::clamp(t0, 0.0, 1.0));
        out.push_back({a, p, false});
        out.push_back({p, b, true});
    } else if (disc > 0 && t0 > 0 && t1 < 1) {
        Vec2 p0 = lerp(a, b, t0), p1 = lerp(a, b, t1);
        out.push_back({a, p0, false});
        out.push_back({p0, p1, true});
        out.push_back({p1, b, false});
    } else {
        out.push_back({a, b, false});
    }
}

std::vector<Step> split_at_circle(const std::vector<Vec2> &poly, double R)
{
    std::vector<Step> steps;
    const size_t n = poly.size();
    std::vector<char> in(n);
    for (size_t k = 0; k < n; k++) in[k] = dot(poly[k], poly[k]) <= R * R;
    for (size_t k = 0; k < n; k++)
        split_edge(poly[k], poly[(k + 1) % n], in[k], in[(k + 1) % n], R, steps);
    return steps;
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

std::vector<Piece> join_into_ring(const std::vector<Step> &steps, double R)
{
    std::vector<Piece> ring;
    const size_t n = steps.size();
    size_t first = std::find_if(steps.begin(), steps.end(), is_side) - steps.begin();
    if (first == n) {
        // No straight side: the polygon holds the whole disk (outside runs sweep a full turn) or
        // misses it (they sweep nothing).
        double total = 0;
        for (const Step &s : steps) total += angle_between(s.a, s.b);
        if (total > kPi) ring.push_back(full_circle(R));
        return ring;
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
    return ring;
}

} // namespace

// ---- the cell ----

Cell clip_cell(const Site &self, const std::vector<Site> &nbrs, double R)
{
    Cell c{{self.x, self.y}, R, {}};
    c.ring = join_into_ring(split_at_circle(cell_polygon_in_square(self, nbrs, R), R), R);
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

void far_candidates(const Cell &c, std::vector<Vec2> &out)
{
    const double s = std::hypot(c.site.x, c.site.y);
    Vec2 opposite = {0, 0};
    if (s > 0) opposite = {-c.R * c.site.x / s, -c.R * c.site.y / s};
    for (const Piece &p : c.ring) {
        out.push_back(p.a);
        if (!p.arc || s == 0) continue; // a site at the origin: every arc point is equally far
        double rel = angle_between(p.a, opposite);
        if (rel < 0) rel += kTwoPi;
        if (rel <= p.sweep) out.push_back(opposite);
    }
}

} // namespace iirtri
