// stri_cell.cpp -- one spherical Voronoi cell computed from its site and Delaunay neighbours: its
// edges, exact area, largest-empty-cap candidates, drawing polygon and shortest incident edge; not
// how sites or neighbours are found (stri_domain.cpp).
//
// On the sphere the Delaunay triangulation is the convex hull of the sites, and the Voronoi vertex
// of a hull face is its outward unit normal -- on the correct side even for the "ghost" faces that
// close the hull when all sites lie in a hemisphere (their caps are larger than a hemisphere).
// Each vertex is computed from its face's three sites in one canonical order (starting at the
// smallest id), so the three cells sharing it use the same bits and the areas tile the sphere.
//
// An edge is turned right-handed about (site - neighbour)/|...| from one vertex to the next; its
// sweep is taken in [-pi/2, 3 pi/2), so rounding cannot flip an edge of length ~0 (co-circular
// sites) to ~2 pi or one of length ~pi (sites nearly on one circle) to the wrong half of the great
// circle. The area is the fan of spherical triangles site - p_k - p_k+1 over each edge, split into
// pieces of at most pi/2, each by Van Oosterom-Strackee's signed formula. A cell is convex and
// contains its site, so the fan covers it exactly once. Sites all on one circle (lunes) and two
// sites (hemispheres) get closed-form areas that tile exactly.
#include "stri_geom.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace iirstri
{
namespace
{

constexpr double kTwoPi = 2 * kPi;
constexpr double kQuarter = kPi / 2;
constexpr uint32_t kNone = UINT32_MAX;
// A cosine further than this from the extreme one (smallest for the farthest candidate, largest
// for the nearest neighbour) cannot tie with it: the angles differ by more than 1e-9 rad, far
// beyond IIR_TRI_TIE_TOL and rounding, so its exact angle is never needed.
constexpr double kBand = 1e-9;

// ---- small geometry ----

Cap_key make_key(uint32_t a, uint32_t b, uint32_t c, uint32_t side)
{
    Cap_key k = {{a, b, c}, side};
    std::sort(k.ids, k.ids + 3);
    return k;
}

// v turned by t radians right-handed about the unit axis k (Rodrigues).
Vec3 rotate(Vec3 v, Vec3 k, double t)
{
    double c = std::cos(t), s = std::sin(t);
    return c * v + s * cross(k, v) + ((1 - c) * dot(k, v)) * k;
}

// Signed angle from a to b right-handed about the unit axis k, in (-pi, pi].
double turn(Vec3 a, Vec3 b, Vec3 k)
{
    return std::atan2(dot(k, cross(a, b)), dot(a, b));
}

// Signed area of the spherical triangle abc (positive when counter-clockwise seen from outside).
double triangle_area(Vec3 a, Vec3 b, Vec3 c)
{
    return 2 * std::atan2(dot(a, cross(b, c)), 1 + dot(a, b) + dot(b, c) + dot(c, a));
}

// Pieces of at most pi/2 an edge of `sweep` radians is cut into.
int pieces(double sweep)
{
    return sweep > kQuarter ? (int)std::ceil(sweep / kQuarter) : 1;
}

// A unit vector perpendicular to the unit vector e (deterministic).
Vec3 perpendicular(Vec3 e)
{
    double ax = std::fabs(e.x), ay = std::fabs(e.y), az = std::fabs(e.z);
    Vec3 axis = ax <= ay && ax <= az ? Vec3{1, 0, 0} : ay <= az ? Vec3{0, 1, 0} : Vec3{0, 0, 1};
    return normalize(cross(e, axis));
}

// The point of the bisector of s and t (unit normal e = (s - t)/|s - t|) farthest from both: the
// antipode of their midpoint, projected onto the bisector so that it is equidistant to both to
// rounding. Symmetric in s and t (bit for bit). False when s and t are antipodal (every bisector
// point is then pi/2 from both).
bool far_bisector_point(Vec3 s, Vec3 t, Vec3 e, Vec3 &out)
{
    Vec3 q = -(s + t);
    Vec3 c = q - dot(q, e) * e;
    double l = norm(c);
    if (!(l > 1e-300)) return false;
    out = (1 / l) * c;
    return true;
}

// The Voronoi vertex of the hull face abc (counter-clockwise seen from outside): its outward unit
// normal, computed from the rotation of (a, b, c) that starts at the smallest id.
Vec3 face_vertex(const Site &a, const Site &b, const Site &c)
{
    const Site *p[3] = {&a, &b, &c};
    int r = a.id < b.id ? (a.id < c.id ? 0 : 2) : (b.id < c.id ? 1 : 2);
    Vec3 p0 = p[r]->p, p1 = p[(r + 1) % 3]->p, p2 = p[(r + 2) % 3]->p;
    Vec3 n = cross(p1 - p0, p2 - p0);
    double l = norm(n);
    // Sites IIR_STRI_MIN_DIST apart never give a zero normal; keep a unit vector regardless.
    return l > 0 ? (1 / l) * n : normalize(p0 + p1 + p2);
}

Arc make_arc(const Site &self, const Site &nbr, Vec3 from, Vec3 to, Cap_key key)
{
    Arc a;
    a.from = from;
    a.to = to;
    a.axis = normalize(self.p - nbr.p);
    a.sweep = turn(from, to, a.axis);
    if (a.sweep < -kQuarter) a.sweep += kTwoPi;
    a.nbr = nbr;
    a.key = key;
    return a;
}

// Area of the part of the cell between its site and one edge: the fan over the edge's pieces.
double sector_area(Vec3 s, const Arc &a)
{
    const int m = pieces(a.sweep);
    double total = 0;
    Vec3 p = a.from;
    for (int i = 1; i <= m; i++) {
        Vec3 q = i == m ? a.to : rotate(a.from, a.axis, a.sweep * i / m);
        total += triangle_area(s, p, q);
        p = q;
    }
    return total;
}

// ---- the ring, by dimension ----

void ring_dim2(const Cell_input &in, std::vector<Arc> &ring)
{
    assert(in.n >= 3 && "a vertex of a triangulated sphere has three neighbours or more");
    const Site &s = in.self;
    const size_t k = in.n;
    // Vertex j is the face (s, t_j, t_j+1); edge j runs from vertex j-1 to vertex j.
    const Vec3 last = face_vertex(s, in.nbrs[k - 1], in.nbrs[0]);
    Vec3 from = last;
    for (size_t j = 0; j < k; j++) {
        const Site &prev = in.nbrs[(j + k - 1) % k], &t = in.nbrs[j], &next = in.nbrs[(j + 1) % k];
        const Vec3 to = j + 1 == k ? last : face_vertex(s, t, next);
        ring.push_back(make_arc(s, t, from, to, make_key(s.id, prev.id, t.id, 0)));
        from = to;
    }
}

// Angle of p around the circle's axis.
double circle_angle(const Frame &f, Vec3 p)
{
    return std::atan2(dot(p, f.w), dot(p, f.u));
}

// Counter-clockwise angle from site s to site t around the circle, in (0, 2 pi].
double gap(const Frame &f, Vec3 s, Vec3 t)
{
    double d = circle_angle(f, t) - circle_angle(f, s);
    return d <= 0 ? d + kTwoPi : d;
}

// A lune between the circle's poles N and -N: counter-clockwise around the site, N, the edge with
// the previous site, -N, the edge with the next one. Returns the area: twice the lune's angle,
// half of each gap to a neighbour, so that the lunes tile the sphere exactly.
double ring_dim1(const Cell_input &in, std::vector<Arc> &ring)
{
    assert(in.n == 2);
    const Site &s = in.self;
    const Frame &f = in.frame;
    double g0 = gap(f, s.p, in.nbrs[0].p), g1 = gap(f, s.p, in.nbrs[1].p);
    const Site &next = g0 < g1 ? in.nbrs[0] : in.nbrs[1];
    const Site &prev = g0 < g1 ? in.nbrs[1] : in.nbrs[0];
    const double gap_next = std::min(g0, g1), gap_prev = kTwoPi - std::max(g0, g1);
    Arc a = make_arc(s, prev, f.N, -f.N, make_key(s.id, prev.id, next.id, 0));
    Arc b = make_arc(s, next, -f.N, f.N, make_key(s.id, prev.id, next.id, 1));
    a.sweep = b.sweep = kPi;
    ring.push_back(a);
    ring.push_back(b);
    return gap_prev + gap_next;
}

// A hemisphere: one edge all around, starting at the bisector point farthest from both sites.
void ring_dim0(const Cell_input &in, std::vector<Arc> &ring)
{
    const Site &s = in.self, &t = in.nbrs[0];
    Vec3 e = normalize(s.p - t.p), c;
    if (!far_bisector_point(s.p, t.p, e, c)) c = perpendicular(e);
    Arc a = make_arc(s, t, c, c, make_key(s.id, t.id, kNone, 0));
    a.sweep = kTwoPi;
    ring.push_back(a);
}

} // namespace

// ---- the cell ----

const Cell &make_cell(const Cell_input &in, Cell_scratch &scratch)
{
    Cell &c = scratch.cell;
    c.in = in;
    c.ring.clear();
    switch (in.dim) {
    case 2:
        ring_dim2(in, c.ring);
        c.area = 0;
        for (const Arc &a : c.ring) c.area += sector_area(in.self.p, a);
        break;
    case 1:
        c.area = ring_dim1(in, c.ring);
        break;
    case 0:
        ring_dim0(in, c.ring);
        c.area = kTwoPi;
        break;
    default:
        c.area = 2 * kTwoPi;
        break;
    }
    return c;
}

// Whether p (on the great circle of the arc) lies strictly inside the arc. Edges shorter than pi
// (nearly all) need only two orientation signs; longer ones an angle.
bool inside_arc(const Arc &a, Vec3 p)
{
    if (a.sweep < kPi)
        return a.sweep > 0 && dot(a.axis, cross(a.from, p)) > 0 && dot(a.axis, cross(p, a.to)) > 0;
    double psi = turn(a.from, p, a.axis);
    if (psi < 0) psi += kTwoPi;
    return psi > 0 && psi < a.sweep;
}

void cap_candidates(const Cell &c, std::vector<Candidate> &out)
{
    const Site &s = c.in.self;
    const size_t first = out.size();
    auto add = [&](Vec3 p, Cap_key key) { out.push_back({p, dot(s.p, p), key}); };
    if (c.in.dim < 0) add(-s.p, make_key(s.id, kNone, kNone, 0));
    if (c.in.dim == 0) add(c.ring[0].from, c.ring[0].key);
    for (size_t k = 0; c.in.dim > 0 && k < c.ring.size(); k++) {
        const Arc &a = c.ring[k];
        add(a.from, a.key);
        // The edge's point farthest from both sites, when it lies inside the edge. An edge shorter
        // than pi with both ends within pi/2 of the site (nearly every edge) stays in the half of
        // its great circle nearest the site, away from that point.
        if (a.sweep < kPi && dot(s.p, a.from) > 0 && dot(s.p, a.to) > 0) continue;
        Vec3 p;
        if (far_bisector_point(s.p, a.nbr.p, a.axis, p) && inside_arc(a, p))
            add(p, make_key(s.id, a.nbr.id, kNone, 0));
    }
    // r holds the cosine so far: the exact angle only where it can matter.
    double cmin = 2;
    for (size_t k = first; k < out.size(); k++) cmin = std::min(cmin, out[k].r);
    for (size_t k = first; k < out.size(); k++)
        out[k].r = out[k].r <= cmin + kBand ? angle_between(s.p, out[k].c) : -1;
}

void cell_polygon(const Cell &c, std::vector<Vec3> &out)
{
    out.clear();
    for (const Arc &a : c.ring) {
        out.push_back(a.from);
        const int m = pieces(a.sweep);
        for (int i = 1; i < m; i++) out.push_back(rotate(a.from, a.axis, a.sweep * i / m));
    }
}

Frame circle_frame(const Site *sites, size_t n)
{
    assert(n >= 3);
    const Vec3 a = sites[0].p;
    Vec3 b = a, c = a;
    double best = -1;
    for (size_t i = 0; i < n; i++) {
        Vec3 d = sites[i].p - a;
        if (dot(d, d) > best) best = dot(d, d), b = sites[i].p;
    }
    best = -1;
    for (size_t i = 0; i < n; i++) {
        Vec3 x = cross(b - a, sites[i].p - a);
        if (dot(x, x) > best) best = dot(x, x), c = sites[i].p;
    }
    Frame f;
    f.N = normalize(cross(b - a, c - a));
    if (dot(f.N, a) < 0) f.N = -f.N;
    f.u = normalize(a - dot(a, f.N) * f.N);
    f.w = cross(f.N, f.u);
    return f;
}

// ---- the shortest incident edge ----

bool shortest_incident(const Site &self, const Site *nbrs, size_t n, iirtri::Edge_key &out)
{
    // Only the neighbours whose cosine is within kBand of the nearest's can be shortest.
    double cmax = -2;
    for (size_t k = 0; k < n; k++) cmax = std::max(cmax, dot(self.p, nbrs[k].p));
    bool first = true;
    for (size_t k = 0; k < n; k++) {
        if (!(dot(self.p, nbrs[k].p) >= cmax - kBand)) continue;
        const Site &young = self.id > nbrs[k].id ? self : nbrs[k];
        const Site &old = self.id > nbrs[k].id ? nbrs[k] : self;
        iirtri::Edge_key e = {angle_between(young.p, old.p), young.id, old.id};
        if (first || iirtri::shorter(e, out)) out = e;
        first = false;
    }
    return n > 0;
}

} // namespace iirstri
