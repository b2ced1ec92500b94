// errors.js -- the panel's error banners: one per kind of request (params, scene, light, camera,
// snapshot, record, save, ...), each saying what the server refused and why, each with a dismiss
// button, and each gone by itself once a later request of the same kind succeeds (a corrected params
// clears the params error; a scene switch that works clears a scene error). Which request an error
// belongs to is requests.js's business; this file only shows them.

const LABELS = {
    params: 'parameters',
    scene: 'scene',
    light: 'light',
    camera: 'camera',
    pick: 'aim',
    snapshot: 'snapshot',
    record: 'recording',
    save: 'save',
    notes: 'not rendered',
    hello: 'session',
    other: 'server',
};
const OTHER_MS = 15000; // errors of no request (rate limit, render failures) go after this long

export class ErrorBanners {
    constructor(container) {
        this.container = container; // #errors
        this.banners = new Map(); // kind -> {el, seq}
    }

    // text: what to show; seq: the seq of the request it answers (0 when none); note: a notice (what
    // the method leaves out of the scene), not a refusal.
    show(kind, text, seq = 0, note = false) {
        this.dismiss(kind);
        const el = document.createElement('div');
        el.className = note ? 'error note' : 'error';
        el.dataset.kind = kind;
        el.setAttribute('role', 'alert');
        const label = document.createElement('b');
        label.textContent = `${LABELS[kind] || kind}: `;
        const body = document.createElement('span');
        body.className = 'error-text';
        body.textContent = text;
        const close = document.createElement('button');
        close.type = 'button';
        close.className = 'dismiss';
        close.title = 'Dismiss';
        close.setAttribute('aria-label', 'Dismiss this error');
        close.textContent = '×';
        close.addEventListener('click', () => this.dismiss(kind));
        el.append(label, body, close);
        this.container.append(el);
        const b = { el, seq, timer: 0 };
        if (kind === 'other') b.timer = setTimeout(() => this.dismiss(kind), OTHER_MS);
        this.banners.set(kind, b);
    }

    // A request of this kind with this seq succeeded: the older error of its kind goes.
    succeeded(kind, seq) {
        const b = this.banners.get(kind);
        if (b && !(seq < b.seq)) this.dismiss(kind);
    }

    dismiss(kind) {
        const b = this.banners.get(kind);
        if (!b) return;
        clearTimeout(b.timer);
        b.el.remove();
        this.banners.delete(kind);
    }

    // kind -> text of the banners shown (for tests and the console).
    list() {
        return Object.fromEntries([...this.banners].map(([k, b]) => [k, b.el.querySelector('.error-text').textContent]));
    }
}
