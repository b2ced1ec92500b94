// domain.js -- a live drawing of a light's VPL domain from `domain` messages, drawn into the unit
// disk (a spot's disk, a glTF spot's cap disk, a point light's sphere by an equal-area map, a sun's
// disk: the message's `map` names it, and a line above the caption says it): the disk, each VPL site's Voronoi
// cell clipped to it, the Delaunay edges, the sites (new ones and null samples marked) and the sites
// removed by the frame shown. Drawing and its caption only; main.js says which domain and which
// frame are shown, and of which light.
//
// One frame counter: the caption names the frame on screen (the server's frame id, as the image's
// overlay and the stats panel do). A refinement pass keeps the set of the frame it refines, so its
// drawing is that frame's sites with nothing new and nothing removed; while frames stream faster than
// domains come (at most one every 100 ms) the caption says which frame the drawing is of. Removed
// sites are drawn for the frame that removed them only: they do not pile up.

const COLORS = {
    disk: '#15171a',
    rim: '#5a5f66',
    axis: '#2c3036',
    cell: 'rgba(120,150,190,0.35)',
    cellNew: 'rgba(80,255,140,0.16)',
    edge: 'rgba(110,170,255,0.55)',
    site: '#ffc83c',
    siteNew: '#50ff8c',
    siteNull: '#8a8a8a',
    removed: '#ff5a5a',
    text: '#9aa0a6',
};

export class DomainView {
    // canvas; caption: the line under it (which frame, the counts); what: the line naming the map and
    // the light (empty without them).
    constructor(canvas, caption, what) {
        this.canvas = canvas;
        this.caption = caption;
        this.what = what;
        this.ctx = canvas.getContext('2d');
        this.domain = null;
        this.shown = null; // {frameId, pass, base}: the frame on screen; base: the interactive frame it refines
        this.note = 'waiting for the first frame'; // the caption when there is no drawing
        this.of = ''; // which light the domain is of ("light 'key'"), '' to say nothing
        this.removedDrawn = 0; // crosses in the drawing (for tests)
        new ResizeObserver(() => this.resize()).observe(canvas);
        this.resize();
    }

    resize() {
        const dpr = window.devicePixelRatio || 1;
        const w = Math.max(1, Math.round(this.canvas.clientWidth * dpr));
        if (this.canvas.width !== w || this.canvas.height !== w) {
            this.canvas.width = w;
            this.canvas.height = w;
        }
        this.draw();
    }

    // domain: the `domain` message of the current method, or null; shown: the frame on screen
    // {frameId, pass, base} or null; note: the caption without a drawing ("pt has no VPL domain");
    // of: which light it is of ("light 'key'"), '' when there is only one.
    update(domain, shown, note, of = '') {
        this.domain = domain;
        this.shown = shown;
        this.note = note;
        this.of = of;
        this.draw();
    }

    // "light 'key' · cap disk": what the drawing is ('' when the message names no map).
    head() {
        const d = this.domain;
        return d && d.sites ? [this.of, d.map].filter(Boolean).join(' · ') : '';
    }

    draw() {
        const c = this.ctx;
        const S = this.canvas.width;
        const dpr = window.devicePixelRatio || 1;
        c.clearRect(0, 0, S, S);
        this.removedDrawn = 0;
        const d = this.domain;
        // the line keeps its height when empty (a no-break space), so that the panel's layout -- and
        // with it the canvas, were a scrollbar to come and go -- does not move when a map arrives
        if (this.what) this.what.textContent = this.head() || '\u00a0';
        if (!d || !d.sites) {
            this.caption.textContent = this.note;
            return;
        }
        const R = S * 0.46; // unit disk radius in canvas pixels
        const map = ([x, y]) => [S / 2 + x * R, S / 2 - y * R]; // +y up, as on the disk
        this.drawDisk(c, S, R, dpr);
        // What the drawing is of: the frame shown, a refinement of it, or an earlier frame.
        const f = this.shown;
        const refined = f && f.pass > 0 && f.base === d.frame;
        const current = f && f.pass === 0 && f.frameId === d.frame;
        c.save();
        c.beginPath();
        c.arc(S / 2, S / 2, R + dpr, 0, 2 * Math.PI);
        c.clip();
        this.drawCells(c, d, map, dpr, !refined);
        this.drawEdges(c, d, map, dpr);
        c.restore();
        this.drawSites(c, d, map, dpr, !refined);
        if (!refined) this.drawRemoved(c, d, map, dpr);
        const nulls = d.sites.filter((s) => s[3] & 2).length;
        const sets = `${d.sites.length} VPLs${nulls ? ` (${nulls} null)` : ''}`;
        if (refined) {
            this.caption.textContent = `frame ${f.frameId} · pass ${f.pass} of frame ${d.frame} · ${sets} · unchanged`;
            return;
        }
        const fresh = d.sites.filter((s) => s[3] & 1).length;
        const removed = d.removed ? d.removed.length : 0;
        const head = current || !f ? `frame ${d.frame}` : `frame ${d.frame} (on screen: frame ${f.frameId})`;
        this.caption.textContent = `${head} · ${sets} · ${fresh} new · ${removed} removed`;
    }

    drawDisk(c, S, R, dpr) {
        c.fillStyle = COLORS.disk;
        c.beginPath();
        c.arc(S / 2, S / 2, R, 0, 2 * Math.PI);
        c.fill();
        c.strokeStyle = COLORS.axis;
        c.lineWidth = dpr;
        c.beginPath();
        c.moveTo(S / 2 - R, S / 2);
        c.lineTo(S / 2 + R, S / 2);
        c.moveTo(S / 2, S / 2 - R);
        c.lineTo(S / 2, S / 2 + R);
        c.stroke();
        c.strokeStyle = COLORS.rim;
        c.lineWidth = 1.5 * dpr;
        c.beginPath();
        c.arc(S / 2, S / 2, R, 0, 2 * Math.PI);
        c.stroke();
    }

    drawCells(c, d, map, dpr, markNew) {
        if (!d.cells) return;
        c.lineWidth = dpr;
        c.strokeStyle = COLORS.cell;
        d.cells.forEach((poly, i) => {
            if (!poly || poly.length < 3) return;
            c.beginPath();
            poly.forEach((p, k) => {
                const [x, y] = map(p);
                if (k === 0) c.moveTo(x, y);
                else c.lineTo(x, y);
            });
            c.closePath();
            const site = d.sites[i];
            if (markNew && site && site[3] & 1) {
                c.fillStyle = COLORS.cellNew;
                c.fill();
            }
            c.stroke();
        });
    }

    drawEdges(c, d, map, dpr) {
        if (!d.edges) return;
        c.strokeStyle = COLORS.edge;
        c.lineWidth = 0.8 * dpr;
        c.beginPath();
        for (const [i, j] of d.edges) {
            const a = d.sites[i];
            const b = d.sites[j];
            if (!a || !b) continue;
            const [x0, y0] = map(a);
            const [x1, y1] = map(b);
            c.moveTo(x0, y0);
            c.lineTo(x1, y1);
        }
        c.stroke();
    }

    // Dots shrink with the site count so that 4096 sites stay readable: about a sixth of the mean
    // spacing of N sites on the disk, between 1 and 2.2 CSS pixels.
    drawSites(c, d, map, dpr, markNew) {
        const spacing = ((this.canvas.width * 0.46) / dpr) * Math.sqrt(Math.PI / Math.max(1, d.sites.length));
        const r = Math.min(2.2, Math.max(1, spacing / 6)) * dpr;
        for (const s of d.sites) {
            const [x, y] = map(s);
            const flags = markNew ? s[3] : s[3] & ~1;
            c.beginPath();
            if (flags & 2) {
                c.arc(x, y, r, 0, 2 * Math.PI);
                c.strokeStyle = COLORS.siteNull;
                c.lineWidth = dpr;
                c.stroke();
                continue;
            }
            c.arc(x, y, flags & 1 ? 1.5 * r : r, 0, 2 * Math.PI);
            c.fillStyle = flags & 1 ? COLORS.siteNew : COLORS.site;
            c.fill();
        }
    }

    // The sites this domain's frame removed, as red crosses (where they were on the disk).
    drawRemoved(c, d, map, dpr) {
        const removed = d.removed || [];
        const r = 4 * dpr;
        c.strokeStyle = COLORS.removed;
        c.lineWidth = 1.6 * dpr;
        c.beginPath();
        for (const p of removed) {
            const [x, y] = map(p);
            c.moveTo(x - r, y - r);
            c.lineTo(x + r, y + r);
            c.moveTo(x + r, y - r);
            c.lineTo(x - r, y + r);
        }
        c.stroke();
        this.removedDrawn = removed.length;
    }
}
