// saving.js -- the panel's "save the lights and camera as a scene" controls (docs/protocol.md `save`):
// Download asks for the sidecar and downloads it (NAME.scene.json, NAME the name typed made a scene
// name by downloadName, to put in SCENES/NAME/ and render with `iird render NAME`; Enter does it
// where the server does not write scenes); Save on server asks the daemon to write it as a new scene NAME, which
// then appears in the scene picker. A daemon started without --allow-save refuses that: the button
// is then disabled and says why (known from welcome.limits.allow_save when the daemon sends it, else
// from its first refusal). Sending, downloading and the picker are the caller's (main.js).

const NAME_RE = /^[A-Za-z0-9_.-]{1,100}$/;

// The name typed as a file and scene name for Download: a trailing .scene.json (or .json) goes,
// what a scene name cannot hold (spaces, /, ...) becomes _, leading dots and runs of dots go; ''
// when nothing usable is left (or it is builtin, the built-in box's name).
export function downloadName(typed) {
    const n = typed.trim().replace(/(\.scene)?\.json$/i, '').replace(/[^A-Za-z0-9_.-]+/g, '_')
        .replace(/\.{2,}/g, '.').replace(/^\.+/, '').slice(0, 100);
    return NAME_RE.test(n) && n !== 'builtin' ? n : '';
}
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
        // Enter saves on the server, or downloads where the server does not write scenes
        this.name.addEventListener('keydown', (e) => {
            if (e.key === 'Enter') this.ask(!this.blocked);
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

    // Download (onServer false) names the file after the name typed (downloadName), else
    // SCENE_view; Save on server sends the name typed, checked.
    ask(onServer) {
        this.name.classList.remove('invalid');
        let msg = { type: 'save' };
        const typed = this.name.value.trim();
        let file = downloadName(typed) || `${this.h.scene()}_view`;
        if (onServer) {
            if (this.blocked) return;
            const name = this.checkedName();
            if (!name) return;
            msg = { type: 'save', name };
            file = name;
        }
        const seq = this.h.send(msg, { file, typed, onServer });
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
            const typed = req && req.typed;
            const as = typed && typed !== file ? ` ("${typed}" as a scene name: letters, digits, _ - .)` : '';
            this.say(`downloaded ${file}.scene.json${as}: put it in SCENES/${file}/ and run iird render ${file} --scenes SCENES`);
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
