// curtain.js -- what the image area says instead of (or over) a frame: "loading conference…" or
// "rendering the first frame…" while a switch is under way (over the greyed image), and, when the
// server refused a scene or method because the method cannot render that scene, why and what would
// work (the server's "-- try pt or ir"), with a button for each. Text and buttons only; the image
// itself is view.js's, and main.js decides when to say what.

export class Curtain {
    constructor(root) {
        this.root = root; // #curtain
        this.box = root.querySelector('.curtain-box');
        this.title = root.querySelector('#curtain-title');
        this.text = root.querySelector('#curtain-text');
        this.actions = root.querySelector('#curtain-actions');
        this.close = root.querySelector('#curtain-close');
        this.close.addEventListener('click', () => this.hide());
        // It sits on the image: its clicks and wheel are its own, not aiming or moving the light.
        for (const ev of ['pointerdown', 'wheel', 'contextmenu']) this.box.addEventListener(ev, (e) => e.stopPropagation());
        this.mode = 'none';
    }

    // A switch under way: the image under it is greyed by the caller.
    loading(title, text = '') {
        this.set('loading', title, text, []);
    }

    // The server refused a request; actions: [{label, title, run()}] that would work instead.
    refused(title, text, actions = []) {
        this.set('refused', title, text, actions);
    }

    hide() {
        this.mode = 'none';
        this.root.hidden = true;
        this.root.dataset.mode = 'none';
    }

    set(mode, title, text, actions) {
        this.mode = mode;
        this.root.dataset.mode = mode;
        this.title.textContent = title;
        this.text.textContent = text;
        this.text.hidden = !text;
        this.actions.replaceChildren(
            ...actions.map((a) => {
                const b = document.createElement('button');
                b.type = 'button';
                b.textContent = a.label;
                if (a.title) b.title = a.title;
                b.addEventListener('click', () => {
                    this.hide();
                    a.run();
                });
                return b;
            }),
        );
        this.close.hidden = mode !== 'refused';
        this.root.hidden = false;
    }
}

// The methods a server message proposes: "... -- try pt or ir" -> ['pt', 'ir'] (empty when none).
export function alternatives(message) {
    const m = /--\s*try\s+(.+?)\s*$/.exec(message || '');
    if (!m) return [];
    return m[1].split(/\s*,\s*|\s+or\s+/).map((s) => s.trim()).filter((s) => /^[a-z0-9_]+$/i.test(s));
}
