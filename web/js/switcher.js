// switcher.js -- scene and method switches as the user sees them, so the image is always the scene
// and method the panel says: asking for one greys the image at once and says what is loading
// (curtain.js); the gate (gate.js) holds every frame until the `state` reply and every frame of an
// older generation after it; the first frame of the new state ends the loading; a refused switch puts
// the panel and the image back to what the session shows and says in the image area why, with what
// would work (the server's "-- try pt or ir") as buttons. Every `scene` and `params` message goes
// through here (all of them bump the generation). Not the error banners (main.js, errors.js).

import * as P from './protocol.js';
import { alternatives } from './curtain.js';

export class Switcher {
    // parts: {gate, view, curtain, panel, send(msg, details) -> seq, state() -> the page's model,
    // busy(on): a scene is loading (main.js disables the light and camera controls meanwhile)}
    constructor(parts) {
        Object.assign(this, parts);
        this.sceneLoading = false;
    }

    // ---- asking ----

    // shown: the scene the session shows (the page's model's unless told: after a reconnect the new
    // session shows its startup scene while the page still says its own).
    scene(name, shown = this.state().scene) {
        const s = this.state();
        const seq = this.send(P.scene(name), { name });
        if (seq < 0) return this.panel.setState(s); // not sent: the picker shows the scene shown
        this.gate.asked({ seq, kind: 'scene', name });
        if (name === shown) return seq; // "reset view": the same scene, its own light and camera
        this.begin(`loading ${name}…`, `${shown} goes; ${name} is shown with ${s.params.method} once it has loaded`);
        this.sceneLoading = true;
        this.busy(true);
        return seq;
    }

    params(fields) {
        const s = this.state();
        const seq = this.send(P.params(fields), { method: fields.method });
        if (seq < 0) {
            this.panel.setState(s);
            return seq;
        }
        this.gate.asked({ seq, kind: 'params', method: fields.method });
        if (fields.method && fields.method !== s.params.method) this.begin(`switching to ${fields.method}…`, `${s.scene} with ${fields.method}`);
        return seq;
    }

    begin(title, text) {
        this.view.grey();
        this.view.setVpls(null);
        this.curtain.loading(title, text);
    }

    // ---- replies ----

    // A `state`; req: the request it answers (or null); sameRender: see gate.stated.
    stated(msg, req, sameRender = false) {
        this.gate.stated(msg.seq, msg.generation, sameRender);
        const switched = req && (req.kind === 'scene' || (req.kind === 'params' && req.method));
        if (switched && this.curtain.mode === 'refused') this.curtain.hide();
        if (this.gate.switching) return;
        this.done();
        if (this.view.greyed) {
            this.curtain.loading(`rendering the first frame…`, `${msg.scene} with ${msg.params.method}`);
        }
    }

    // An error answering switch `req`: the session still shows what it showed.
    refused(msg, req) {
        this.gate.refused(req.seq);
        if (this.gate.switching) return; // a newer switch is under way; its reply decides
        this.done();
        const s = this.state();
        this.view.restore();
        this.panel.setState(s);
        const cannot = msg.code === 'unsupported' || msg.code === 'scene_error';
        const what = req.kind === 'scene' ? req.name : req.method;
        if (!cannot || !what) {
            if (this.curtain.mode === 'loading') this.curtain.hide();
            return;
        }
        const alt = alternatives(msg.message);
        let title;
        let actions;
        if (req.kind === 'scene') {
            title = msg.code === 'scene_error'
                ? `${req.name} did not load; ${s.scene} is still shown`
                : `${s.params.method} cannot render ${req.name}; ${s.scene} is still shown`;
            actions = alt.map((m) => ({
                label: `open ${req.name} with ${m}`,
                title: `switch the method to ${m}, then the scene to ${req.name}`,
                run: () => {
                    this.params({ method: m });
                    this.scene(req.name);
                },
            }));
        } else {
            title = `${req.method} cannot render ${s.scene}; ${s.params.method} is still used`;
            actions = alt.filter((m) => m !== s.params.method).map((m) => ({ label: `use ${m}`, title: `switch the method to ${m}`, run: () => this.params({ method: m }) }));
        }
        this.curtain.refused(title, msg.message, actions);
    }

    // A frame of the current state is on screen: the switch is over.
    drawn() {
        if (this.curtain.mode === 'loading') this.curtain.hide();
    }

    // A welcome: a new session drops the switches asked of the old one.
    welcome(w, newSession) {
        if (newSession) this.gate.reset(w.state.generation);
        else this.gate.stated(undefined, w.state.generation);
        if (!this.gate.switching) this.done();
    }

    done() {
        if (!this.sceneLoading) return;
        this.sceneLoading = false;
        this.busy(false);
    }
}
