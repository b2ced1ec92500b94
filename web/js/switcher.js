// switcher.js -- scene and method switches as the user sees them, so the image is always the scene
// and method the panel says: asking for one greys the image at once and says what is loading
// (curtain.js); the gate (gate.js) holds every frame until the `state` reply and every frame of an
// older generation after it; the first frame of the new state ends the loading; a refused switch puts
// the panel and the image back to what the session shows and says in the image area why, with what
// would work (the server's "-- try pt or ir") as buttons, also when the refusal comes as an error
// after the switch's `state` (lateRefusal). Every `scene` and `params` message goes
// through here (all of them bump the generation). Not the error banners (main.js, errors.js).

import * as P from './protocol.js';
import { alternatives } from './curtain.js';

export class Switcher {
    // parts: {gate, view, curtain, panel, send(msg, details) -> seq, state() -> the page's model,
    // methods() -> welcome.methods, busy(): a scene is loading or a reset view awaits its reply
    // (main.js disables the light and camera controls meanwhile)}
    constructor(parts) {
        Object.assign(this, parts);
        this.sceneLoading = false;
        this.answered = new Map(); // seq -> switch answered by a state: an error may still follow it
    }

    // ---- asking ----

    // shown: the scene the session shows (the page's model's unless told: after a reconnect the new
    // session shows its startup scene while the page still says its own).
    scene(name, shown = this.state().scene) {
        const s = this.state();
        const seq = this.send(P.scene(name), { name, from: { scene: shown, method: s.params.method } });
        if (seq < 0) return this.panel.setState(s); // not sent: the picker shows the scene shown
        this.gate.asked({ seq, kind: 'scene', name });
        // "reset view": the same scene, its own light and camera (back to it while another loads:
        // the curtain says so); no curtain, but no moves until its reply either
        if (name === shown && !this.sceneLoading) {
            this.busy(true);
            return seq;
        }
        this.begin(`loading ${name}…`, name === shown ? `${name} again, with ${s.params.method}`
            : `${shown} goes; ${name} is shown with ${s.params.method} once it has loaded`);
        this.sceneLoading = true;
        this.busy(true);
        return seq;
    }

    // restore: the page puts back the method a session could not render (no curtain of its own:
    // the refusal's stays).
    params(fields, { restore = false } = {}) {
        const s = this.state();
        const seq = this.send(P.params(fields), { method: fields.method, fields: Object.keys(fields), restore, from: { scene: s.scene, method: s.params.method } });
        if (seq < 0) {
            this.panel.setState(s);
            return seq;
        }
        this.gate.asked({ seq, kind: 'params', method: fields.method });
        if (fields.method && fields.method !== s.params.method && !restore) this.begin(`switching to ${fields.method}…`, `${s.scene} with ${fields.method}`);
        return seq;
    }

    // The scene the newest switch under way asks for (the picker says it), or null.
    pendingScene() {
        let name = null;
        for (const r of this.gate.pending.values()) if (r.kind === 'scene') name = r.name;
        return name;
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
        const switched = req && !msg.superseded && (req.kind === 'scene' || (req.kind === 'params' && req.method));
        if (req && !msg.superseded && (req.kind === 'scene' || req.kind === 'params')) {
            this.answered.set(msg.seq, req);
            if (this.answered.size > 16) this.answered.delete(this.answered.keys().next().value);
        }
        if (switched && !req.restore && this.curtain.mode === 'refused') this.curtain.hide();
        if (this.gate.switching) return;
        this.done();
        // a refusal says what happened until the user moves on (its frames come under it)
        if (this.view.greyed && this.curtain.mode !== 'refused') {
            this.curtain.loading(`rendering the first frame…`, `${msg.scene} with ${msg.params.method}`);
        }
    }

    // The switch a `state` answered with this seq (an error about it may come after: the session
    // took it, then could not render it), or null.
    answeredSwitch(seq) {
        return (seq && this.answered.get(seq)) || null;
    }

    // An error after the state of switch `req`: the session took the scene or method but cannot
    // render it (radiosity's "at most 200000 patches" when its worker creates it; a memory refusal,
    // which the server follows by a state taking the session back). The image area says so and what
    // would work; a method switch the session cannot render is undone (its previous method asked
    // for again) unless the server does it itself.
    lateRefusal(msg, req) {
        this.answered.delete(req.seq);
        if (this.gate.switching) return; // a newer switch is under way; its reply decides
        if (req.kind === 'scene' && this.gate.replaced(req.seq)) return;
        this.done();
        // parameters of the method shown (the image never greyed): the banner and the field say it
        if (req.kind === 'params' && !req.method && !this.view.greyed) return;
        const s = this.state();
        const failed = req.kind === 'params' ? req.method || s.params.method : s.params.method;
        const scene = req.kind === 'scene' ? req.name : s.scene;
        const from = req.from || {};
        let alt = alternatives(msg.message);
        if (!alt.length) alt = this.methods().map((m) => m.name).filter((m) => m !== failed);
        if (from.method && alt.includes(from.method)) alt = [from.method, ...alt.filter((m) => m !== from.method)];
        const undo = msg.code === 'unsupported' && req.kind === 'params' && !req.restore && from.method && from.method !== failed &&
            from.scene === s.scene && s.params.method === failed;
        let title = `${failed} cannot render ${scene}`;
        if (undo) title += `; ${from.method} is used again`;
        else if (msg.code !== 'unsupported') title = `${failed} on ${scene} was refused`;
        const actions = alt.filter((m) => !(undo && m === from.method)).slice(0, 4).map((m) => ({
            label: `use ${m}`,
            title: `switch the method to ${m}`,
            run: () => this.params({ method: m }),
        }));
        if (req.kind === 'scene' && from.scene && from.scene !== scene) {
            actions.push({ label: `back to ${from.scene}`, title: `switch the scene back to ${from.scene}`, run: () => this.scene(from.scene) });
        }
        this.curtain.refused(title, msg.message, actions);
        if (undo) this.params({ method: from.method }, { restore: true });
    }

    // An error answering switch `req`: the session still shows what it showed.
    refused(msg, req) {
        this.gate.refused(req.seq);
        if (this.gate.switching) return; // a newer switch is under way; its reply decides
        if (req.kind === 'scene' && this.gate.replaced(req.seq)) return; // a newer scene was shown since
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

    // No switch waits for its reply: light and camera moves are taken again.
    done() {
        this.sceneLoading = false;
        this.busy(false);
    }
}
