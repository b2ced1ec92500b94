// inspect.js -- window.iir: a read-only view of the page for the browser tests and the console,
// built from main.js's parts. It changes nothing.
//
//   framesReceived, framesDrawn, framesHeld (frames the gate did not show), lastFrame (header of the
//   newest drawn frame), drawn (the last drawn frames: frameId, generation, pass, t), shownStats (the
//   stats of the frame on screen), lastDomain, lastStats, methods (welcome.methods), connected,
//   state (the page's model), generation (newest state's), switching (a switch awaits its state),
//   inputSeq (newest input sent), inputPending (a light or camera move waits for the next animation
//   frame to be sent), latencyMs, errors (kind -> banner text), fieldErrors (params field ->
//   why the value typed there was refused, shown next to it), curtain ({mode, title,
//   text}), greyed, gizmo (where the selected light is drawn, frame pixels), gizmos (where each light
//   is drawn: {name, x, y, visible, offscreen}), selected (index of the selected light in
//   state.lights), vplChart (the VPL chart's rows), domainRemovedDrawn (removed-site crosses in the
//   domain drawing), vplsDrawn (VPL dots drawn on the image)

const clone = (x) => JSON.parse(JSON.stringify(x));

export function inspector({ app, gate, controls, errors, curtain, view, charts, domainView, panel }) {
    return Object.freeze({
        get methods() {
            return app.methods;
        },
        get framesReceived() {
            return app.framesReceived;
        },
        get framesDrawn() {
            return app.framesDrawn;
        },
        get framesHeld() {
            return app.framesHeld;
        },
        get lastFrame() {
            return app.lastFrame;
        },
        get drawn() {
            return app.drawn.slice();
        },
        get shownStats() {
            return app.shown ? app.stats.get(app.shown.frameId) || null : null;
        },
        get lastDomain() {
            return app.lastDomain;
        },
        get lastStats() {
            return app.lastStats;
        },
        get inputSeq() {
            return app.inputSeq;
        },
        get inputPending() {
            return controls.inputPending;
        },
        get latencyMs() {
            return app.latencyMs;
        },
        get connected() {
            return app.connected;
        },
        get state() {
            return app.state && clone(app.state);
        },
        get generation() {
            return gate.generation;
        },
        get switching() {
            return gate.switching;
        },
        get errors() {
            return errors.list();
        },
        get fieldErrors() {
            return panel ? panel.listFieldErrors() : {};
        },
        get curtain() {
            return { mode: curtain.mode, title: curtain.title.textContent, text: curtain.text.textContent };
        },
        get greyed() {
            return view.greyed;
        },
        get gizmo() {
            return { ...view.gizmoAt };
        },
        get gizmos() {
            return view.gizmosAt.map((g) => ({ ...g }));
        },
        get vplsDrawn() {
            return view.vplsDrawn || 0;
        },
        get selected() {
            return app.selected;
        },
        get vplChart() {
            return charts.vplRows(); // [t, count, kept, invalidated, inserted, deleted]
        },
        get domainRemovedDrawn() {
            return domainView.removedDrawn;
        },
    });
}
