// view.js -- the image: a canvas that shows the newest frame (JPEG decoded with createImageBitmap),
// scaled to fill its container at the frame's aspect ratio, and an overlay canvas above it for the
// VPLs, the lights' gizmos (gizmo.js) and the aim marker. Maps pointer positions to frame pixels and
// finds the light whose gizmo is under one.
// Greys the image while a switch is under way and puts the last frame back when it is refused. Not
// input handling (controls.js), not which frames may be shown (gate.js: the mayShow predicate).
//
// Decoding is latest-wins like the server: while one JPEG decodes, only the newest frame that
// arrives meanwhile is kept; older ones are dropped, never queued.

import { drawGizmo } from './gizmo.js';

export class View {
    constructor(container) {
        this.container = container;
        this.canvas = document.createElement('canvas');
        this.canvas.id = 'frame';
        this.canvas.width = 512;
        this.canvas.height = 384;
        this.overlay = document.createElement('canvas');
        this.overlay.id = 'overlay';
        container.append(this.canvas, this.overlay);
        this.ctx = this.canvas.getContext('2d', { willReadFrequently: false });
        this.octx = this.overlay.getContext('2d');
        this.decoding = false;
        this.next = null; // the newest frame waiting for the decoder
        this.drawnId = 0;
        this.onDrawn = () => {};
        this.mayShow = () => true; // checked again after decoding: the gate may have closed meanwhile
        this.bitmap = null; // the frame drawn last, kept to put it back after a refused switch
        this.greyed = false;
        this.gizmo = null; // {lights, selected, camera, madeUp}: the lights to draw over the image
        this.gizmoAt = { x: NaN, y: NaN, visible: false }; // where the selected one was drawn, frame pixels
        this.gizmosAt = []; // where each light was drawn ({name, x, y, visible, offscreen}), in order
        this.vpls = null; // domain.vpls of the newest domain message: [[sx, sy, flags], ...]
        this.showVpls = true;
        this.marker = null; // {x, y, kind} in frame pixels while dragging
        this.cssW = 0;
        this.cssH = 0;
        new ResizeObserver(() => this.fit()).observe(container);
        this.fit();
    }

    // header: parseFrame's result (kind 1). Shows it once decoded; calls onDrawn(header).
    show(header) {
        // A frame replaced before it was drawn hands on the input time it answered (main.js's sentAt).
        if (this.next && header.sentAt == null) header.sentAt = this.next.sentAt;
        this.next = header;
        if (!this.decoding) this.decodeNext();
    }

    async decodeNext() {
        const h = this.next;
        this.next = null;
        if (!h) return;
        this.decoding = true;
        try {
            const bitmap = await createImageBitmap(new Blob([h.payload], { type: 'image/jpeg' }));
            // One decode at a time, frames arrive in order: never older.
            if (this.mayShow(h)) this.draw(h, bitmap);
            else bitmap.close();
        } catch (e) {
            console.warn(`iir: frame ${h.frameId} did not decode: ${e.message || e}`);
        }
        this.decoding = false;
        if (this.next) this.decodeNext();
    }

    draw(h, bitmap) {
        if (this.canvas.width !== bitmap.width || this.canvas.height !== bitmap.height) {
            this.canvas.width = bitmap.width;
            this.canvas.height = bitmap.height;
            this.fit();
        }
        this.ctx.drawImage(bitmap, 0, 0);
        if (this.bitmap) this.bitmap.close();
        this.bitmap = bitmap;
        this.drawnId = h.frameId;
        this.setGreyed(false);
        this.onDrawn(h);
    }

    // The image greyed out and darkened (a switch is under way: what it shows is about to go).
    grey() {
        if (this.greyed) return;
        const c = this.ctx;
        c.save();
        c.filter = 'grayscale(1) brightness(0.35) blur(2px)';
        if (this.bitmap) c.drawImage(this.bitmap, 0, 0);
        else {
            c.fillStyle = '#202226';
            c.fillRect(0, 0, this.canvas.width, this.canvas.height);
        }
        c.restore();
        this.setGreyed(true);
    }

    // The last frame drawn, as it was (a switch was refused: the session still shows it).
    restore() {
        if (!this.greyed) return;
        if (this.bitmap) this.ctx.drawImage(this.bitmap, 0, 0);
        this.setGreyed(false);
    }

    setGreyed(on) {
        if (this.greyed === on) return;
        this.greyed = on;
        this.canvas.classList.toggle('greyed', on);
        this.drawOverlay();
    }

    // Largest rectangle of the frame's aspect ratio inside the container, centred.
    fit() {
        const box = this.container.getBoundingClientRect();
        const aspect = this.canvas.width / this.canvas.height;
        let w = Math.max(1, Math.floor(box.width));
        let h = Math.floor(w / aspect);
        if (h > box.height) {
            h = Math.max(1, Math.floor(box.height));
            w = Math.floor(h * aspect);
        }
        this.cssW = w;
        this.cssH = h;
        for (const c of [this.canvas, this.overlay]) {
            c.style.width = `${w}px`;
            c.style.height = `${h}px`;
            c.style.left = `${Math.floor((box.width - w) / 2)}px`;
            c.style.top = `${Math.floor((box.height - h) / 2)}px`;
        }
        const dpr = window.devicePixelRatio || 1;
        this.overlay.width = Math.round(w * dpr);
        this.overlay.height = Math.round(h * dpr);
        this.drawOverlay();
    }

    // Client (CSS) coordinates to frame pixels; inside reports whether the point is on the image.
    toFrame(clientX, clientY) {
        const r = this.canvas.getBoundingClientRect();
        const x = ((clientX - r.left) / r.width) * this.canvas.width;
        const y = ((clientY - r.top) / r.height) * this.canvas.height;
        return { x, y, inside: x >= 0 && y >= 0 && x < this.canvas.width && y < this.canvas.height };
    }

    // CSS pixels per frame pixel (for world-space drag scaling).
    cssPerPixel() {
        return this.cssW / this.canvas.width;
    }

    frameSize() {
        return { width: this.canvas.width, height: this.canvas.height };
    }

    // vpls: domain.vpls ([[x, y, flags], ...]) or null; markNew: draw the new ones as new.
    setVpls(vpls, markNew = true) {
        this.vpls = vpls;
        this.vplsMarkNew = markNew;
        this.drawOverlay();
    }

    // g: {lights, selected (index), camera, madeUp} or null.
    setGizmo(g) {
        this.gizmo = g;
        this.drawOverlay();
    }

    setMarker(marker) {
        this.marker = marker;
        this.drawOverlay();
    }

    drawOverlay() {
        const o = this.octx;
        const W = this.overlay.width;
        const H = this.overlay.height;
        o.clearRect(0, 0, W, H);
        const sx = W / this.canvas.width;
        const sy = H / this.canvas.height;
        const dpr = window.devicePixelRatio || 1;
        this.gizmoAt = { x: NaN, y: NaN, visible: false };
        this.gizmosAt = [];
        this.vplsDrawn = 0;
        if (this.greyed) return; // nothing of the old state over a greyed image
        if (this.showVpls && this.vpls) this.drawVpls(o, sx, sy, dpr);
        if (this.gizmo && this.drawnId) this.drawGizmos(o, sx, sy, dpr);
        if (this.marker) this.drawMarker(o, this.marker.x * sx, this.marker.y * sy, dpr);
    }

    // Every light's gizmo, the selected one last (on top).
    drawGizmos(o, sx, sy, dpr) {
        const { lights, selected, camera, madeUp } = this.gizmo;
        const order = lights.map((_, i) => i).filter((i) => i !== selected);
        if (selected >= 0 && selected < lights.length) order.push(selected);
        const at = [];
        for (const i of order) {
            const g = { light: lights[i], camera, madeUp, selected: i === selected, width: this.canvas.width, height: this.canvas.height };
            at[i] = { name: lights[i].name, ...drawGizmo(o, g, sx, sy, dpr) };
        }
        this.gizmosAt = at;
        if (at[selected]) this.gizmoAt = { ...at[selected] };
        delete this.gizmoAt.name;
    }

    // The index of the light whose gizmo (its handle or off-screen arrow) is within radiusCss CSS
    // pixels of frame point (x, y), the nearest; -1 when none is.
    gizmoNear(x, y, radiusCss = 12) {
        const r = radiusCss / Math.max(1e-6, this.cssPerPixel());
        let best = -1;
        let bestD = r;
        this.gizmosAt.forEach((g, i) => {
            const d = Math.hypot(g.x - x, g.y - y);
            if (d <= bestD) {
                best = i;
                bestD = d;
            }
        });
        return best;
    }

    drawVpls(o, sx, sy, dpr) {
        const r = 1.9 * dpr;
        o.lineWidth = dpr;
        for (const [x, y, f] of this.vpls) {
            if (x < 0 || y < 0) continue;
            this.vplsDrawn++;
            const flags = this.vplsMarkNew ? f : f & ~1;
            const px = x * sx;
            const py = y * sy;
            o.beginPath();
            o.arc(px, py, (flags & 1 ? 1.4 : 1) * (flags & 4 ? 0.75 : 1) * r, 0, 2 * Math.PI);
            if (flags & 2) {
                o.strokeStyle = 'rgba(150,150,150,0.8)';
                o.stroke();
            } else if (flags & 4) { // a later bounce: drawn apart from the light's own VPLs
                o.fillStyle = flags & 1 ? 'rgba(120,220,255,0.95)' : 'rgba(70,140,255,0.85)';
                o.fill();
                o.strokeStyle = 'rgba(0,0,0,0.6)';
                o.stroke();
            } else if (flags & 1) {
                o.fillStyle = 'rgba(80,255,140,0.95)';
                o.fill();
                o.strokeStyle = 'rgba(0,0,0,0.7)';
                o.stroke();
            } else {
                o.fillStyle = 'rgba(255,200,60,0.85)';
                o.fill();
                o.strokeStyle = 'rgba(0,0,0,0.6)';
                o.stroke();
            }
        }
    }

    drawMarker(o, x, y, dpr) {
        const r = 9 * dpr;
        o.strokeStyle = this.marker.kind === 'miss' ? 'rgba(255,90,90,0.9)' : 'rgba(255,255,255,0.9)';
        o.lineWidth = 1.5 * dpr;
        o.beginPath();
        o.arc(x, y, r, 0, 2 * Math.PI);
        o.moveTo(x - 1.8 * r, y);
        o.lineTo(x - 0.5 * r, y);
        o.moveTo(x + 0.5 * r, y);
        o.lineTo(x + 1.8 * r, y);
        o.moveTo(x, y - 1.8 * r);
        o.lineTo(x, y - 0.5 * r);
        o.moveTo(x, y + 0.5 * r);
        o.lineTo(x, y + 1.8 * r);
        o.stroke();
    }
}
