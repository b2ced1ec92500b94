// charts.js -- live charts of the `stats` stream with uPlot (served from web/vendor/uplot/, copied
// from npm by `make web-deps`): per-phase render time stacked over time, fps and input-to-frame
// latency, and VPL counts (the set's size; kept / invalidated / inserted / deleted by the frame's
// step, as vplstats.js reads them: a frame without a VPL step leaves a gap, a new set has no "kept").
// Keeps the last WINDOW_S seconds; redraws at most REDRAW_HZ times a second.

import uPlot from '../vendor/uplot/uPlot.esm.js';
import { vplStep } from './vplstats.js';

const WINDOW_S = 30;
const REDRAW_HZ = 8;
const HEIGHT = 104;

// Known phases in pipeline order with their colours; phases a server reports beyond these are
// appended in grey shades.
const PHASES = [
    ['trace', '#8c6bb1'],
    ['vpls', '#e7ba52'],
    ['shadowmaps', '#e6550d'],
    ['maps', '#e6550d'],
    ['solve', '#e7ba52'],
    ['gather', '#bcbd22'],
    ['gbuffer', '#6b6ecf'],
    ['direct', '#3182bd'],
    ['indirect', '#31a354'],
    ['filter', '#9ecae1'],
    ['display', '#31a354'],
];

const AXIS = {
    stroke: '#8a9097',
    grid: { stroke: 'rgba(255,255,255,0.07)', width: 1 },
    ticks: { stroke: 'rgba(255,255,255,0.15)', width: 1, size: 4 },
    font: '10px system-ui, sans-serif',
};

function alpha(hex, a) {
    const n = parseInt(hex.slice(1), 16);
    return `rgba(${(n >> 16) & 255},${(n >> 8) & 255},${n & 255},${a})`;
}

export class Charts {
    constructor(container) {
        this.container = container;
        this.t0 = performance.now();
        this.phaseNames = [];
        this.phaseData = null; // [t, ...per phase raw]
        this.perf = [[], [], [], []]; // t, fps, client latency, render ms
        this.vpl = [[], [], [], [], [], []]; // t, count, kept, invalidated, inserted, deleted
        this.plots = {};
        this.dirty = false;
        this.timer = setInterval(() => this.redraw(), 1000 / REDRAW_HZ);
        this.width = 300;
        new ResizeObserver(() => this.resize()).observe(container);
    }

    resize() {
        const w = Math.max(160, Math.floor(this.container.clientWidth));
        if (w === this.width && Object.keys(this.plots).length) return;
        this.width = w;
        for (const p of Object.values(this.plots)) p.setSize({ width: w, height: HEIGHT });
    }

    // stats: the `stats` message; latency: the page's input-to-frame latency (ms) or null.
    push(stats, latency) {
        const t = (performance.now() - this.t0) / 1000;
        const phases = stats.phases || {};
        const names = orderPhases(Object.keys(phases));
        if (names.join() !== this.phaseNames.join()) this.makePhaseChart(names);
        this.phaseData[0].push(t);
        names.forEach((n, i) => this.phaseData[i + 1].push(phases[n] || 0));
        push(this.perf, [t, stats.fps ?? null, latency, stats.total_ms ?? null]);
        // Only frames with a VPL step have points: refinement passes keep their frame's set, pt has none.
        const st = vplStep(stats);
        const step = st.kind === 'new' || st.kind === 'updated';
        const val = (x) => (step ? x : null);
        push(this.vpl, [t, val(st.count), val(st.kept), val(st.invalidated), val(st.inserted), val(st.deleted)]);
        for (const d of [this.phaseData, this.perf, this.vpl]) trim(d, t - WINDOW_S);
        if (!this.plots.perf) this.makeFixedCharts();
        this.dirty = true;
    }

    // The VPL chart's newest n rows: [t, count, kept, invalidated, inserted, deleted] (null: no point).
    vplRows(n = 50) {
        const len = this.vpl[0].length;
        const rows = [];
        for (let i = Math.max(0, len - n); i < len; i++) rows.push(this.vpl.map((col) => col[i]));
        return rows;
    }

    redraw() {
        if (!this.dirty) return;
        this.dirty = false;
        if (this.plots.phases) this.plots.phases.setData(stack(this.phaseData));
        if (this.plots.perf) this.plots.perf.setData(this.perf);
        if (this.plots.vpl) this.plots.vpl.setData(this.vpl);
        // Without the pointer on a chart its legend shows the newest values.
        for (const p of Object.values(this.plots)) {
            if (p.cursor.left >= 0) continue;
            let idx = p.data[0].length - 1;
            while (idx > 0 && p.data[1][idx] == null) idx--;
            if (idx >= 0) p.setLegend({ idx });
        }
    }

    // ---- chart set-up ----

    // Stacked areas: series k is the sum of phases 1..k, the band between k and k-1 is filled with
    // phase k's colour, and the legend shows each phase's own time.
    makePhaseChart(names) {
        if (this.plots.phases) this.plots.phases.destroy();
        this.phaseNames = names;
        this.phaseData = [[], ...names.map(() => [])];
        const colour = (n, i) => (PHASES.find((p) => p[0] === n) || [n, ['#777', '#999', '#bbb'][i % 3]])[1];
        const series = [{ label: 't', value: (u, x) => (x == null ? '' : `${x.toFixed(1)} s`) }];
        names.forEach((n, i) => {
            const c = colour(n, i);
            series.push({
                label: n,
                stroke: c,
                width: 1,
                fill: alpha(c, 0.55),
                value: (u, val, si, di) => (di == null ? '–' : (this.phaseData[si][di] ?? 0).toFixed(1)),
                points: { show: false },
            });
        });
        const bands = names.slice(1).map((_, i) => ({ series: [i + 2, i + 1], fill: alpha(colour(names[i + 1], i + 1), 0.55) }));
        this.plots.phases = this.plot($('#chart-phases'), 'ms', series, { bands, stacked: true });
    }

    makeFixedCharts() {
        const pts = { show: false };
        this.plots.perf = this.plot($('#chart-perf'), 'ms', [
            { label: 't' },
            { label: 'fps', scale: 'fps', stroke: '#e7ba52', width: 1.2, points: pts, value: fix(1) },
            { label: 'latency ms', stroke: '#ff7f7f', width: 1.2, points: pts, value: fix(0), spanGaps: true },
            { label: 'render ms', stroke: '#6baed6', width: 1, points: pts, value: fix(1) },
        ], { fpsAxis: true });
        this.plots.vpl = this.plot($('#chart-vpl'), '', [
            { label: 't' },
            { label: 'VPLs', stroke: '#d9dde1', width: 1.2, points: pts, value: fix(0), spanGaps: true },
            { label: 'kept', stroke: '#ffc83c', width: 1.2, points: pts, value: fix(0), spanGaps: false },
            { label: 'invalid', stroke: '#ff5a5a', width: 1, points: pts, value: fix(0), spanGaps: true },
            { label: 'inserted', stroke: '#50ff8c', width: 1, points: pts, value: fix(0), spanGaps: true },
            { label: 'deleted', stroke: '#c77dff', width: 1, points: pts, value: fix(0), spanGaps: true },
        ]);
    }

    plot(target, unit, series, extra = {}) {
        const opts = {
            width: this.width,
            height: HEIGHT,
            class: 'chart',
            legend: { show: true, live: true },
            cursor: { drag: { x: false, y: false }, points: { show: false } },
            scales: { x: { time: false }, y: { range: (u, min, max) => [0, Math.max(1, max * 1.1)] } },
            series,
            axes: [
                { ...AXIS, size: 18, values: (u, ticks) => ticks.map((x) => `${Math.round(x)}s`) },
                { ...AXIS, size: 40, label: unit || undefined, labelSize: unit ? 10 : 0, labelFont: AXIS.font },
            ],
        };
        if (extra.bands) opts.bands = extra.bands;
        if (extra.fpsAxis) {
            opts.scales.fps = { range: (u, min, max) => [0, Math.max(10, max * 1.1)] };
            opts.axes.push({ ...AXIS, scale: 'fps', side: 1, size: 28, grid: { show: false }, label: 'fps', labelSize: 10, labelFont: AXIS.font });
        }
        target.replaceChildren();
        return new uPlot(opts, series.map(() => []), target);
    }
}

const $ = (sel) => document.querySelector(sel);
const fix = (d) => (u, x) => (x == null ? '–' : x.toFixed(d));

function orderPhases(keys) {
    const known = PHASES.map((p) => p[0]).filter((n) => keys.includes(n));
    return known.concat(keys.filter((k) => !known.includes(k)).sort());
}

function push(cols, row) {
    row.forEach((x, i) => cols[i].push(x));
}

function trim(cols, tmin) {
    let n = 0;
    while (n < cols[0].length && cols[0][n] < tmin) n++;
    if (n) for (const c of cols) c.splice(0, n);
}

// Cumulative sums of the series after x: row k becomes the sum of rows 1..k.
function stack(data) {
    const out = [data[0]];
    let acc = data[0].map(() => 0);
    for (let i = 1; i < data.length; i++) {
        acc = acc.map((a, j) => a + (data[i][j] || 0));
        out.push(acc);
    }
    return out;
}
