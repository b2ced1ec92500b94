// saving.js -- the panel's "save the lights and camera as a scene" controls (docs/protocol.md `save`):
// Download asks for the sidecar and downloads it (NAME.scene.json, to put in SCENES/NAME/ and render
// with `iird render NAME`); Save on server asks the daemon to write it as a new scene NAME, which
// then appears in the scene picker. A daemon started without --allow-save refuses that: the button
// is then disabled and says why (known from welcome.limits.allow_save when the daemon sends it, else
// from its first refusal). Sending, downloading and the picker are the caller's (main.js).

const NAME_RE = /^[A-Za-z0-9_.-]{1,100}$/;
const NO_SAVE = 'this server does not write scenes (it was started without --allow-save); Download gives the sidecar';

export class SaveControls {
    // handlers: {send(msg, details) -> seq, download(blob, name), scenes(list, more), scene() -> current}
    constructor(root, handlers) {
        this.h = handlers;
        this.name = root.querySelector('#save-name');
        this.server = root.querySelector('#save-server');
        this.info = root.querySelector('#save-info');
        this.serverTitle = this.server.title;
        this.blocked = null; // {reason, scene}: why Save on server cannot work (scene null: any scene)
        root.querySelector('#save-download').addEventListener('click', () => this.ask(false));
        this.server.addEventListener('click', () => this.ask(true));
        this.name.addEventListener('keydown', (e) => {
            if (e.key === 'Enter') this.ask(true);
        });
    }

    // welcome.limits: allow_save false disables Save on server from the start.
    setLimits(limits) {
        if (limits && limits.allow_save === false) this.block(NO_SAVE, null);
        else if (limits && limits.allow_save === true) this.block(null);
    }

    // The scene shown changed: a refusal that was about the scene goes.
    sceneChanged() {
        if (this.blocked && this.blocked.scene !== null && this.blocked.scene !== this.h.scene()) this.block(null);
    }

    block(reason, scene = null) {
        this.blocked = reason ? { reason, scene } : null;
        this.server.disabled = !!reason;
        this.server.title = reason || this.serverTitle;
        if (reason) this.say(`Save on server: ${reason}`);
    }

    // The name typed, checked as the daemon will (a bare name, not builtin), or null (and why).
    checkedName() {
        const n = this.name.value.trim();
        const bad = !NAME_RE.test(n) ? 'a name of letters, digits, _ - . (at most 100)'
            : n.startsWith('.') || n.includes('..') ? 'a name that does not start with . and holds no ..'
            : n === 'builtin' ? 'a name other than builtin' : null;
        if (!bad) return n;
        this.name.classList.add('invalid');
        this.name.title = `the new scene needs ${bad}`;
        this.say(`Save: the new scene needs ${bad}`);
        return null;
    }

    ask(onServer) {
        this.name.classList.remove('invalid');
        let msg = { type: 'save' };
        let file = this.name.value.trim();
        if (onServer) {
            if (this.blocked) return;
            const name = this.checkedName();
            if (!name) return;
            msg = { type: 'save', name };
            file = name;
        }
        if (!NAME_RE.test(file) || file.startsWith('.')) file = `${this.h.scene()}_view`;
        const seq = this.h.send(msg, { file, onServer });
        if (seq > 0) this.say(onServer ? `saving ${file} on the server…` : 'asking for the sidecar…');
    }

    // The `save` reply; req: the request it answers ({file, onServer}).
    saved(msg, req) {
        if (msg.name) {
            if (msg.scenes) this.h.scenes(msg.scenes, msg.scenes_more);
            this.say(`saved as scene ${msg.name} on the server (in the picker; iird render ${msg.name} renders it)`);
        } else {
            const file = (req && req.file) || `${this.h.scene()}_view`;
            const text = `${JSON.stringify(msg.sidecar, null, 2)}\n`;
            this.h.download(new Blob([text], { type: 'application/json' }), `${file}.scene.json`);
            this.say(`downloaded ${file}.scene.json: put it in SCENES/${file}/ and run iird render ${file} --scenes SCENES`);
        }
    }

    // An error answering a save: why Save on server cannot work, or the name it refused.
    refused(msg) {
        if (msg.field !== 'save.name') return;
        if (msg.code === 'unsupported') {
            const always = /--allow-save/.test(msg.message || '');
            const reason = always ? NO_SAVE : msg.message;
            this.block(reason, always ? null : this.h.scene());
        } else {
            this.name.classList.add('invalid');
            this.name.title = msg.message || '';
            this.say('');
        }
    }

    say(text) {
        this.info.textContent = text;
    }
}
