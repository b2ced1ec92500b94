// panel.js -- the side panel's forms and read-outs: scene and method pickers, the parameter form
// built from the parameter tables the welcome carries (welcome.methods[].params for the method's
// group, welcome.settings for the frame group, welcome.limits), the list of lights (each with its
// kind and an on/off switch; a click selects the one the mouse moves) and the selected light's own
// fields (a spot's cone, a glTF spot's inner cone, an area light's size, the intensity), camera
// fields, snapshot and record buttons,
// the live numbers of the frame on screen (its `stats`), the note on a light iird made up, and the
// marking of a refused field. It turns edits into calls of its handlers; it sends nothing itself.
// Charts are charts.js, the domain drawing domain.js, error banners errors.js.

import { fmt } from './vec.js';
import { kindOf } from './gizmo.js';
import { vplStep, describeStep } from './vplstats.js';
import { renderTime } from './protocol.js';

const $ = (sel, root = document) => root.querySelector(sel);
const KIND_NAMES = { point: 'point', spot: 'spot', gltf_spot: 'glTF spot', sun: 'sun', area: 'area' };
const UNITS = { point: 'W/sr', spot: 'W/sr on the axis', gltf_spot: 'W/sr', sun: 'irradiance W/m²', area: 'radiance W/(sr·m²)' };

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

// The frame-time controller's state (stats.ctl, null when target_fps is 0): the rate it holds
// against its target (a running mean of interactive frames only: none before the first drag),
// why it misses it (busy: fewer VPLs bought no time; unreachable even at its floor), its choice
// and its quality floor (ctl_vpls_min, ctl_sm_res_min), which it never goes below.
function describeController(c) {
    if (!c) return 'off';
    const held = c.frames > 0 && c.mean_ms > 0 ? (1000 / c.mean_ms).toFixed(0) : '–';
    let why = '';
    if (!c.frames) why = ' (no interactive frame yet)';
    else if (c.busy) why = ' (busy: fewer VPLs bought no time)';
    else if (!c.reachable) why = ' (unreachable at the floor)';
    const floor = `floor N ${c.vpls_min} · ${c.sm_res_min}²`;
    return `${held}/${(1000 / c.target_ms).toFixed(0)} fps${why} · N ${c.vpls} · n ${c.interleave} · ${c.sm_res}² · ${floor}`;
}

export class Panel {
    // handlers: {scene(name), params(fields), light(fields) (of the selected light),
    // selectLight(index), lightOn(index, on), camera(fields), snapshot(format), record(), fitSize(),
    // resetView()}
    constructor(root, handlers) {
        this.root = root;
        this.h = handlers;
        this.inputs = new Map(); // params field -> input element
        this.state = null;
        this.methods = [];
        this.recording = null; // {since} while recording
        this.selected = 0; // index of the selected light
        this.listKey = ''; // the light list's names and kinds as built
        this.fieldErrors = new Map(); // params field -> why the value typed there was refused
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
        const inner = $('#inner-cone', this.root);
        inner.addEventListener('input', () => ($('#inner-cone-value', this.root).textContent = `${inner.value}°`));
        inner.addEventListener('change', () => this.innerEdited(inner));
        for (const id of ['#size-w', '#size-h']) $(id, this.root).addEventListener('change', () => this.sizeEdited());
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

    setWelcome(w, selected = this.selected) {
        this.setScenes(w.scenes);
        this.methods = w.methods || [];
        this.settings = w.settings || [];
        this.limits = w.limits || {};
        this.formMethod = null;
        this.buildHead();
        this.buildGroup($('#params-frame', this.root), this.settings);
        $('#server', this.root).textContent = `${w.server || 'iird'} · session ${w.session}`;
        this.setState(w.state, selected);
    }

    // The scene picker's names (a save on the server adds one); the scene shown stays picked.
    setScenes(names) {
        const sel = $('#scene', this.root);
        sel.replaceChildren(...names.map((s) => el('option', { value: s, text: s })));
        if (this.state) sel.value = this.state.scene;
    }

    buildHead() {
        const input = el('select', {}, ...this.methods.map((m) => el('option', { value: m.name, text: m.name, title: m.summary || '' })));
        input.id = 'param-method';
        input.name = 'method';
        input.addEventListener('change', () => this.h.params({ method: input.value }));
        this.inputs.set('method', input);
        $('#params-head', this.root).replaceChildren(input); // labelled in index.html
    }

    // One labelled input per table row into `group` (replacing what it held).
    buildGroup(group, rows) {
        for (const [name, input] of this.inputs) if (group.contains(input)) this.inputs.delete(name);
        group.replaceChildren();
        for (const row of rows) {
            const input = this.makeInput(row);
            input.id = `param-${row.name}`;
            input.name = row.name;
            input.title = row.help + (row.unit ? ` (${row.unit})` : '');
            const live = this.maxOf(row);
            if (row.type === 'int' || row.type === 'u64' || row.type === 'float') {
                input.title += ` · [${row.min}, ${live}]${row.max > live ? ` live (iird render: up to ${row.max})` : ''}`;
            }
            input.dataset.title = input.title;
            input.addEventListener('change', () => this.edited(row, input));
            this.inputs.set(row.name, input);
            const label = el('label', { for: input.id, text: row.name.replaceAll('_', ' '), title: input.title });
            const error = el('div', { class: 'field-error', role: 'alert', 'data-field': row.name });
            error.hidden = true;
            group.append(el('div', { class: 'row' }, label, input), error);
            if (this.fieldErrors.has(row.name)) this.showFieldError(row.name, this.fieldErrors.get(row.name));
        }
    }

    // The method group holds the parameters of the method the state names.
    buildMethodGroup(method) {
        if (method === this.formMethod) return;
        const m = this.methods.find((x) => x.name === method);
        this.buildGroup($('#params-method', this.root), m ? m.params : []);
        this.formMethod = method;
    }

    // The most a row may be: a server limit named max_<name> when there is one, else its live max.
    maxOf(row) {
        const limit = this.limits[`max_${row.name}`];
        return limit !== undefined ? Math.min(limit, row.live_max) : row.live_max;
    }

    makeInput(row) {
        if (row.type === 'enum') return el('select', {}, ...row.choices.map((o) => el('option', { value: o, text: o })));
        if (row.type === 'bool') return el('input', { type: 'checkbox' });
        const step = row.type === 'float' ? 'any' : 1;
        return el('input', { type: 'number', min: row.min, max: this.maxOf(row), step });
    }

    // A form edit: the value if it is valid, else the field shows the value in force again and,
    // next to it, why the one typed was refused (until a value of that field is accepted).
    edited(row, input) {
        let value;
        if (row.type === 'bool') value = input.checked;
        else if (row.type === 'enum') value = input.value;
        else {
            value = Number(input.value);
            const min = Number(input.min);
            const max = Number(input.max);
            const int = row.type !== 'float';
            const bad = input.value === '' || !Number.isFinite(value) || value < min || value > max ||
                (int && !Number.isInteger(value));
            if (bad) {
                const typed = input.value === '' ? 'an empty value' : input.value;
                const beyond = row.max > max && value > max && value <= row.max
                    ? ` (${max} is a live session's most; \`iird render\` takes up to ${row.max})` : '';
                const inForce = this.state && this.state.params[row.name] !== undefined ? `; ${this.state.params[row.name]} is in force` : '';
                this.showFieldError(row.name, `${typed} refused: ${row.name} must be ${int ? 'an integer ' : ''}in [${min}, ${max}]${beyond}${inForce}`);
                this.showValue(row.name);
                return;
            }
        }
        this.h.params({ [row.name]: value });
    }

    // The value in force (the state's) back in field `name`.
    showValue(name) {
        const input = this.inputs.get(name);
        const val = this.state && this.state.params[name];
        if (!input || val === undefined) return;
        if (input.type === 'checkbox') input.checked = !!val;
        else input.value = String(val);
    }

    // Why the value typed into params field `name` was refused, next to the field, until cleared.
    showFieldError(name, text) {
        this.fieldErrors.set(name, text);
        const input = this.inputs.get(name);
        if (!input) return;
        input.classList.add('invalid');
        input.title = `${text}\n${input.dataset.title || ''}`;
        const box = this.root.querySelector(`.field-error[data-field="${name}"]`);
        if (box) {
            box.textContent = text;
            box.hidden = false;
        }
    }

    // A value of these params fields was accepted: their errors go.
    clearFieldErrors(names) {
        for (const name of names) {
            if (!this.fieldErrors.delete(name)) continue;
            const input = this.inputs.get(name);
            if (input) {
                input.classList.remove('invalid');
                input.title = input.dataset.title || '';
            }
            const box = this.root.querySelector(`.field-error[data-field="${name}"]`);
            if (box) {
                box.hidden = true;
                box.textContent = '';
            }
        }
    }

    // The field errors shown (name -> text), for tests and the console.
    listFieldErrors() {
        return Object.fromEntries(this.fieldErrors);
    }

    // The scene picker says `name` (a switch to it is under way) instead of the scene shown.
    showScene(name) {
        if (name) $('#scene', this.root).value = name;
    }

    setState(state, selected = this.selected) {
        this.state = state;
        $('#scene', this.root).value = state.scene;
        this.buildMethodGroup(state.params.method);
        for (const [name, input] of this.inputs) {
            const val = state.params[name];
            if (val === undefined) continue;
            if (input.type === 'checkbox') input.checked = !!val;
            else input.value = String(val);
            if (!this.fieldErrors.has(name)) input.classList.remove('invalid');
        }
        const m = this.methods.find((x) => x.name === state.params.method);
        $('#method-summary', this.root).textContent = m && m.summary ? m.summary : '';
        this.setLights(state.lights || (state.light ? [state.light] : []), selected);
        this.setCamera(state.camera);
        $('#light-note', this.root).hidden = !state.default_light;
    }

    // ---- lights ----

    // The light list (rebuilt when the scene's lights change, else updated) and the selected
    // light's fields.
    setLights(lights, selected = this.selected) {
        this.lights = lights;
        this.selected = selected;
        const key = lights.map((L) => `${L.name}\u0000${kindOf(L)}`).join('\u0001');
        if (key !== this.listKey) this.buildLightList(lights);
        this.listKey = key;
        const rows = $('#light-list', this.root).children;
        lights.forEach((L, i) => {
            const row = rows[i];
            row.setAttribute('aria-selected', String(i === selected));
            row.classList.toggle('off', L.on === false);
            const box = row.querySelector('input');
            box.checked = L.on !== false;
        });
        this.setLight(lights[selected]);
    }

    buildLightList(lights) {
        const list = $('#light-list', this.root);
        list.replaceChildren(...lights.map((L, i) => {
            const on = el('input', { type: 'checkbox', title: `${L.name}: on / off`, 'aria-label': `${L.name} on` });
            on.addEventListener('change', () => this.h.lightOn(i, on.checked));
            on.addEventListener('click', (e) => e.stopPropagation());
            const row = el('div', { class: 'light-row', role: 'option', 'data-index': String(i), title: 'select: the mouse moves this light' },
                on, el('span', { class: 'light-name mono', text: L.name }), el('span', { class: 'light-kind dim', text: KIND_NAMES[kindOf(L)] || kindOf(L) }));
            row.addEventListener('click', () => this.h.selectLight(i));
            return row;
        }));
    }

    // The selected light's fields: those of its kind shown, the others hidden.
    setLight(L) {
        if (!L) return;
        const kind = kindOf(L);
        const spot = kind === 'spot' || kind === 'gltf_spot';
        const show = (cls, on) => this.root.querySelectorAll(cls).forEach((e) => (e.hidden = !on));
        show('.k-spot', spot);
        show('.k-gltf', kind === 'gltf_spot');
        show('.k-area', kind === 'area');
        show('.k-pos', kind !== 'sun');
        const cone = $('#cone', this.root);
        if (spot && document.activeElement !== cone) {
            cone.value = String(L.cone_angle);
            $('#cone-value', this.root).textContent = `${Math.round(L.cone_angle)}°`;
        }
        const inner = $('#inner-cone', this.root);
        if (kind === 'gltf_spot' && document.activeElement !== inner) {
            inner.max = String(Math.round(L.cone_angle));
            inner.value = String(L.inner_angle || 0);
            $('#inner-cone-value', this.root).textContent = `${Math.round(L.inner_angle || 0)}°`;
        }
        this.setSize(L);
        const intensity = $('#intensity', this.root);
        intensity.title = `largest RGB channel, ${UNITS[kind] || 'W/sr'}`;
        if (document.activeElement !== intensity && L.intensity) {
            const I = Array.isArray(L.intensity) ? Math.max(...L.intensity) : L.intensity;
            intensity.value = String(Number(I.toPrecision(4)));
        }
        $('#light-pos', this.root).textContent = L.position ? fmt(L.position) : '';
        $('#light-dir', this.root).textContent = kind === 'point' ? 'all around (point light)' : fmt(L.direction);
    }

    setSize(L) {
        if (kindOf(L) !== 'area' || !L.size) return;
        ['#size-w', '#size-h'].forEach((id, k) => {
            const input = $(id, this.root);
            if (document.activeElement !== input) input.value = String(Number(L.size[k].toPrecision(4)));
        });
    }

    innerEdited(input) {
        const x = Number(input.value);
        const L = this.lights && this.lights[this.selected];
        if (L && x <= L.cone_angle) this.h.light({ inner_angle: x });
        else this.flagInvalid(input, 'the inner cone must be within the cone');
    }

    sizeEdited() {
        const w = Number($('#size-w', this.root).value);
        const h = Number($('#size-h', this.root).value);
        const ok = (x) => Number.isFinite(x) && x > 0 && x <= 1e6;
        if (ok(w) && ok(h)) this.h.light({ size: [w, h] });
        else this.flagInvalid($(ok(w) ? '#size-h' : '#size-w', this.root), 'a size must be in (0, 1e6]');
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

    // A refused params field (`params.kmax`): its input shows the state's value again and the
    // server's reason next to it (until a value of that field is accepted).
    flagField(field, text) {
        const name = field && field.startsWith('params.') ? field.slice(7).replace(/\[.*$/, '') : null;
        const input = name && this.inputs.get(name);
        if (!input) return;
        this.showFieldError(name, this.state && this.state.params[name] !== undefined ? `${text}; ${this.state.params[name]} is in force` : text);
        this.showValue(name);
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

    // s: the `stats` of the frame on screen (frame: its header); clientLatency: input-to-frame
    // latency measured by the page (ms) or null. Every number here is that frame's.
    setStats(s, clientLatency, frame) {
        const set = (id, text) => ($(`#${id}`, this.root).textContent = text);
        set('st-fps', s.fps !== undefined ? s.fps.toFixed(1) : '–');
        set('st-latency', clientLatency !== null ? `${clientLatency.toFixed(0)} ms` : '–');
        set('st-server-latency', !s.pass && s.latency_ms !== undefined ? `${s.latency_ms.toFixed(1)} ms` : '–');
        set('st-render', renderTime(s.total_ms || 0, s.reencoded));
        set('st-encode', `${(s.encode_ms || 0).toFixed(1)} ms`);
        set('st-bytes', `${((s.bytes || 0) / 1024).toFixed(1)} KiB`);
        const pass = s.pass ? `pass ${s.pass}${s.converged ? ' ✓' : ''}` : 'interactive';
        set('st-pass', pass);
        set('st-frame', frame ? `${frame.frameId} · ${frame.width}×${frame.height}` : String(s.frame));
        const text = describeStep(vplStep(s), s.method, s.pass);
        set('st-vpls', text.set);
        set('st-vpl-change', text.change);
        const vpl = s.vpl || {};
        set('st-regen', vpl.count ? String(vpl.regenerated || 0) : '–');
        set('st-dropped', String(s.dropped || 0));
        set('st-memory', s.memory_bytes ? `${(s.memory_bytes / 1048576).toFixed(1)} MiB` : '–');
        if (!s.pass) set('st-ctl', describeController(s.ctl));
        this.setCounters(s.method, s.counters || {});
        this.tickRecording();
    }

    // The counters the frame's method declares (the welcome's methods[].counters): a label and a
    // value each, its help as the label's title; none for a method that declares none.
    setCounters(method, values) {
        const box = $('#st-counters', this.root);
        const decl = (this.methods.find((m) => m.name === method) || {}).counters || [];
        const key = `${method}:${decl.map((c) => c.name).join()}`;
        if (box.dataset.key !== key) {
            box.dataset.key = key;
            box.replaceChildren(...decl.flatMap((c) => [
                el('span', { text: c.name.replaceAll('_', ' '), title: c.help }),
                el('b', { id: `st-counter-${c.name}`, text: '–' }),
            ]));
            box.hidden = decl.length === 0;
        }
        for (const c of decl) {
            const v = values[c.name];
            const text = v === undefined ? '–' : c.kind === 'share' ? `${(100 * v).toFixed(1)}%` : String(v);
            $(`#st-counter-${c.name}`, box).textContent = text;
        }
    }
}
