// panel.js -- the side panel's forms and read-outs: scene and method pickers, the parameter form
// built from welcome.state/limits/methods, light and camera fields, snapshot and record buttons,
// the live numbers of the newest `stats`, and the error line. It turns edits into calls of its
// handlers; it sends nothing itself. Charts are charts.js, the domain drawing domain.js.

import { PARAM_FIELDS } from './protocol.js';
import { fmt } from './vec.js';

const $ = (sel, root = document) => root.querySelector(sel);

function el(tag, attrs = {}, ...children) {
    const e = document.createElement(tag);
    for (const [k, val] of Object.entries(attrs)) {
        if (k === 'class') e.className = val;
        else if (k === 'text') e.textContent = val;
        else e.setAttribute(k, val);
    }
    e.append(...children);
    return e;
}

export class Panel {
    // handlers: {scene(name), params(fields), light(fields), camera(fields), snapshot(format),
    // record(), fitSize(), resetView()}
    constructor(root, handlers) {
        this.root = root;
        this.h = handlers;
        this.inputs = new Map(); // params field -> input element
        this.state = null;
        this.methods = [];
        this.recording = null; // {since} while recording
        this.errorTimer = 0;
        this.bindStatic();
    }

    bindStatic() {
        $('#scene', this.root).addEventListener('change', (e) => this.h.scene(e.target.value));
        $('#snapshot-png', this.root).addEventListener('click', () => this.h.snapshot('png'));
        $('#snapshot-exr', this.root).addEventListener('click', () => this.h.snapshot('exr'));
        $('#record', this.root).addEventListener('click', () => this.h.record());
        $('#fit-size', this.root).addEventListener('click', () => this.h.fitSize());
        $('#reset-view', this.root).addEventListener('click', () => this.h.resetView());
        const cone = $('#cone', this.root);
        cone.addEventListener('input', () => ($('#cone-value', this.root).textContent = `${cone.value}°`));
        cone.addEventListener('change', () => this.h.light({ cone_angle: Number(cone.value) }));
        const intensity = $('#intensity', this.root);
        intensity.addEventListener('change', () => {
            const x = Number(intensity.value);
            if (Number.isFinite(x) && x >= 0 && x <= 1e6) this.h.light({ intensity: x });
            else this.flagInvalid(intensity, 'intensity must be in [0, 1e6]');
        });
        const fov = $('#fov', this.root);
        fov.addEventListener('input', () => ($('#fov-value', this.root).textContent = `${fov.value}°`));
        fov.addEventListener('change', () => this.h.camera({ fov: Number(fov.value) }));
    }

    // ---- welcome and state ----

    setWelcome(w) {
        const sel = $('#scene', this.root);
        sel.replaceChildren(...w.scenes.map((s) => el('option', { value: s, text: s })));
        this.methods = w.methods || [];
        this.buildForm(w.limits || {});
        $('#server', this.root).textContent = `${w.server || 'iird'} · session ${w.session}`;
        this.setState(w.state);
    }

    buildForm(limits) {
        const groups = {
            head: $('#params-head', this.root),
            method: $('#params-method', this.root),
            frame: $('#params-frame', this.root),
        };
        for (const g of Object.values(groups)) g.replaceChildren();
        this.inputs.clear();
        for (const f of PARAM_FIELDS) {
            const input = this.makeInput(f, limits);
            input.id = `param-${f.name}`;
            input.name = f.name;
            input.addEventListener('change', () => this.edited(f, input));
            this.inputs.set(f.name, input);
            if (f.group === 'head') {
                groups.head.append(input); // labelled in index.html, beside the scene picker
                continue;
            }
            const label = el('label', { for: input.id, text: f.label || f.name });
            groups[f.group].append(el('div', { class: 'row' }, label, input));
        }
    }

    makeInput(f, limits) {
        if (f.kind === 'method') {
            return el('select', {}, ...this.methods.map((m) => el('option', { value: m.name, text: m.name, title: m.summary || '' })));
        }
        if (f.kind === 'enum') return el('select', {}, ...f.options.map((o) => el('option', { value: o, text: o })));
        if (f.kind === 'bool') return el('input', { type: 'checkbox' });
        const max = f.limit && limits[f.limit] !== undefined ? limits[f.limit] : f.max;
        const attrs = { type: 'number', min: f.min, max, step: f.step || 1 };
        return el('input', attrs);
    }

    // A form edit: the value if it is valid, else the field marked and nothing sent.
    edited(f, input) {
        let value;
        if (f.kind === 'bool') value = input.checked;
        else if (f.kind === 'method' || f.kind === 'enum') value = input.value;
        else {
            value = Number(input.value);
            const min = Number(input.min);
            const max = Number(input.max);
            const bad = input.value === '' || !Number.isFinite(value) || value < min || value > max ||
                (f.kind === 'int' && !Number.isInteger(value));
            if (bad) {
                this.flagInvalid(input, `${f.name} must be ${f.kind === 'int' ? 'an integer ' : ''}in [${min}, ${max}]`);
                return;
            }
        }
        input.classList.remove('invalid');
        this.h.params({ [f.name]: value });
    }

    setState(state) {
        this.state = state;
        $('#scene', this.root).value = state.scene;
        for (const [name, input] of this.inputs) {
            const val = state.params[name];
            if (val === undefined) continue;
            if (input.type === 'checkbox') input.checked = !!val;
            else input.value = String(val);
            input.classList.remove('invalid');
        }
        const m = this.methods.find((x) => x.name === state.params.method);
        $('#method-summary', this.root).textContent = m && m.summary ? m.summary : '';
        this.setLight(state.light);
        this.setCamera(state.camera);
    }

    setLight(L) {
        if (!L) return;
        const cone = $('#cone', this.root);
        if (document.activeElement !== cone) {
            cone.value = String(L.cone_angle);
            $('#cone-value', this.root).textContent = `${Math.round(L.cone_angle)}°`;
        }
        const intensity = $('#intensity', this.root);
        if (document.activeElement !== intensity && L.intensity) {
            const I = Array.isArray(L.intensity) ? Math.max(...L.intensity) : L.intensity;
            intensity.value = String(Number(I.toPrecision(4)));
        }
        $('#light-pos', this.root).textContent = fmt(L.position);
        $('#light-dir', this.root).textContent = fmt(L.direction);
    }

    setCamera(C) {
        if (!C) return;
        const fov = $('#fov', this.root);
        if (document.activeElement !== fov) {
            fov.value = String(C.fov);
            $('#fov-value', this.root).textContent = `${Math.round(C.fov)}°`;
        }
        $('#cam-pos', this.root).textContent = fmt(C.position);
        $('#cam-target', this.root).textContent = fmt(C.target);
    }

    // ---- errors ----

    // msg: an `error` reply. Marks the named params field (its value goes back to the state).
    showError(text, field) {
        const line = $('#error', this.root);
        line.textContent = text;
        line.hidden = false;
        clearTimeout(this.errorTimer);
        this.errorTimer = setTimeout(() => (line.hidden = true), 8000);
        const name = field && field.startsWith('params.') ? field.slice(7).replace(/\[.*$/, '') : null;
        const input = name && this.inputs.get(name);
        if (input) {
            this.flagInvalid(input, text);
            if (this.state) this.setState(this.state);
            input.classList.add('invalid');
        }
    }

    flagInvalid(input, text) {
        input.classList.add('invalid');
        input.title = text;
        setTimeout(() => input.classList.remove('invalid'), 3000);
    }

    // ---- record ----

    setRecording(on) {
        const b = $('#record', this.root);
        this.recording = on ? { since: performance.now() } : null;
        b.classList.toggle('recording', on);
        b.textContent = on ? '■ Stop' : '● Record';
        this.tickRecording();
    }

    tickRecording() {
        const info = $('#record-info', this.root);
        if (!this.recording) return;
        info.textContent = `recording ${((performance.now() - this.recording.since) / 1000).toFixed(1)} s`;
    }

    setRecordInfo(text) {
        $('#record-info', this.root).textContent = text;
    }

    // ---- live numbers ----

    // s: the `stats` message; clientLatency: input-to-frame latency measured by the page (ms) or null.
    setStats(s, clientLatency, frame) {
        const set = (id, text) => ($(`#${id}`, this.root).textContent = text);
        set('st-fps', s.fps !== undefined ? s.fps.toFixed(1) : '–');
        set('st-latency', clientLatency !== null ? `${clientLatency.toFixed(0)} ms` : '–');
        // Server latency and VPL counts belong to interactive frames; refinement passes keep them.
        if (!s.pass) this.interactive = s;
        const live = this.interactive || s;
        set('st-server-latency', live.latency_ms !== undefined ? `${live.latency_ms.toFixed(1)} ms` : '–');
        set('st-render', `${(s.total_ms || 0).toFixed(1)} ms`);
        set('st-encode', `${(s.encode_ms || 0).toFixed(1)} ms`);
        set('st-bytes', `${((s.bytes || 0) / 1024).toFixed(1)} KiB`);
        const pass = s.pass ? `pass ${s.pass}${s.converged ? ' ✓' : ''}` : 'interactive';
        set('st-pass', pass);
        set('st-frame', frame ? `${frame.frameId} · ${frame.width}×${frame.height}` : String(s.frame));
        const vpl = live.vpl || {};
        set('st-vpls', vpl.count !== undefined ? `${vpl.valid}/${vpl.count}` : '–');
        set('st-vpl-change', vpl.count !== undefined ? `+${vpl.inserted} −${vpl.deleted} ✗${vpl.invalidated}` : '–');
        set('st-regen', vpl.regenerated !== undefined ? String(vpl.regenerated) : '–');
        set('st-dropped', String(s.dropped || 0));
        set('st-memory', s.memory_bytes ? `${(s.memory_bytes / 1048576).toFixed(1)} MiB` : '–');
        this.tickRecording();
    }
}
