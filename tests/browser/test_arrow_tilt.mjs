// test_arrow_tilt.mjs -- the arrow keys move the spot's light pool the way they point on the screen,
// by roughly equal steps, from any aim (issue 26, item 2), on the built-in Cornell box (the spot at
// the ceiling pointing straight down in the reset view). The pool is where the spot's axis meets the
// floor (y = 0), projected into the frame with the camera (harness `project`): from the reset view
// ↓ moves it down the screen and ↑ up, each press by a similar step (no flip between two aims);
// from a tilted aim ← → ↑ ↓ move it left, right, up, down. The moved light is the session's (its
// `state` after the frames settle), not only the page's model.
// Keys pressed faster than the page sends (in one task): a reset after a move wins in the page and
// the session alike.
// Screenshots: arrow_tilt_down.png (after ↓ ×4 from the reset view) in $IIR_TEST_TMP (harness
// shotPath).
//
// Usage (as ctest runs it): node tests/browser/test_arrow_tilt.mjs IIRD SOURCE_DIR

import path from 'node:path';
import * as H from './harness.mjs';

const [IIRD, SRC] = process.argv.slice(2);
const { check, log } = H;

const PRESSES = 4; // per arrow and aim (each waits for the session's state: ~1-2 s a press under ASan)
const MAX_ANGLE_DEG = 30; // a step's direction on the screen against the arrow's
const STEP_RATIO = 2.5; // largest step over smallest, per run of presses
const MIN_STEP_PX = 0.5; // of a 256x192 frame (2° toward the camera moves the pool ~1.2 px)

// The pool of the session's light (its state after the frames settle), in frame pixels.
async function pool(page) {
    await H.settle(page, 1, 800);
    const s = await page.evaluate(() => ({ L: window.iir.state.light, cam: window.iir.state.camera, w: window.iir.lastFrame.width, h: window.iir.lastFrame.height }));
    const { position: p, direction: d } = s.L;
    if (!(d[1] < -1e-6)) return { d, p: null };
    const t = -p[1] / d[1];
    const hit = [p[0] + t * d[0], 0, p[2] + t * d[2]];
    return { d, p: H.project(s.cam, s.w, s.h, hit) };
}

// Presses key n times, reads the pool after each; checks direction (dx, dy on the screen) and steps.
async function run(page, key, want, label) {
    const at = [await pool(page)];
    for (let i = 0; i < PRESSES; i++) {
        await page.keyboard.press(key);
        at.push(await pool(page));
    }
    log(`${label}: pool ${at.map((a) => (a.p ? `(${a.p.x.toFixed(1)}, ${a.p.y.toFixed(1)})` : 'none')).join(' ')}; directions ${at.map((a) => `[${a.d.map((x) => x.toFixed(3)).join(',')}]`).join(' ')}`);
    const steps = [];
    let worst = 0;
    for (let i = 1; i < at.length; i++) {
        if (!at[i].p || !at[i - 1].p) return check(false, `${label}: the spot's axis meets the floor at every step`);
        const dx = at[i].p.x - at[i - 1].p.x;
        const dy = at[i].p.y - at[i - 1].p.y;
        const len = Math.hypot(dx, dy);
        steps.push(len);
        const cos = (dx * want[0] + dy * want[1]) / Math.max(1e-9, len);
        worst = Math.max(worst, Math.acos(Math.max(-1, Math.min(1, cos))) * 180 / Math.PI);
    }
    const lo = Math.min(...steps);
    const hi = Math.max(...steps);
    check(worst < MAX_ANGLE_DEG && lo > MIN_STEP_PX,
        `${label}: every press moves the pool ${want[1] < 0 ? 'up' : want[1] > 0 ? 'down' : want[0] < 0 ? 'left' : 'right'} the screen (worst ${worst.toFixed(1)}° off the arrow, steps ${steps.map((s) => s.toFixed(1)).join(', ')} px)`);
    check(hi / lo < STEP_RATIO, `${label}: by similar steps (largest/smallest ${(hi / lo).toFixed(2)} < ${STEP_RATIO})`);
    return at;
}

async function reset(page) {
    await page.keyboard.press('0');
    await H.waitFor(page, () => !window.iir.switching && Math.abs(window.iir.state.light.direction[1] + 1) < 1e-6);
}

// Keys pressed in one task (no animation frame between them: a key's light move is sent on the
// next one), then the session settles: a reset pressed after a move wins over it, and a move pressed
// during a reset (before its reply) is not taken. Either way the page's spot is the session's, which
// is the reset's `state` reply's light, no light message going out after the reset's scene message.
async function keysInOneTask(page, keys, label) {
    const n = await page.evaluate(() => window.__wire.length);
    await page.evaluate((keys) => {
        for (const key of keys) window.dispatchEvent(new KeyboardEvent('keydown', { key, bubbles: true, cancelable: true }));
    }, keys);
    await H.settle(page, 1, 800);
    const { wire, d } = await page.evaluate((n) => ({ wire: window.__wire.slice(n).filter((m) => m.dir === 'out').map((m) => m.type), d: window.iir.state.light.direction }), n);
    const after = wire.slice(wire.lastIndexOf('scene') + 1);
    check(wire.includes('scene') && !after.includes('light') && Math.abs(d[1] + 1) < 1e-6,
        `${label}: the reset wins in the page and the session (sent ${wire.join(', ')}; the page's spot points [${d.map((x) => x.toFixed(3))}])`);
}

async function main() {
    const { daemon, page } = await H.openSmallSession(IIRD, SRC);
    await page.click('#frame', { position: { x: 2, y: 2 }, button: 'right' }).catch(() => {});
    await page.locator('#stage').focus().catch(() => {});
    await page.evaluate(() => document.activeElement && document.activeElement.blur());
    const s0 = await page.evaluate(() => window.iir.state.light);
    log(`the spot: at [${s0.position}] pointing [${s0.direction}]`);
    check(Math.abs(s0.direction[1] + 1) < 1e-6, 'the reset view has the spot straight down');

    const down = await run(page, 'ArrowDown', [0, 1], 'reset view, ↓');
    await H.screenRGB(page, '#viewport', 256, 192, H.shotPath('arrow_tilt_down.png'));
    const zs = down.map((a) => a.d[2]);
    check(zs.every((z, i) => i === 0 || z > zs[i - 1]), `reset view, ↓: the aim goes steadily toward the camera (direction z ${zs.map((z) => z.toFixed(3)).join(' ')})`);
    await reset(page);
    await run(page, 'ArrowUp', [0, -1], 'reset view, ↑');
    await reset(page);
    await run(page, 'ArrowRight', [1, 0], 'reset view, →');
    await reset(page);
    await run(page, 'ArrowLeft', [-1, 0], 'reset view, ←');

    // a tilted aim: shift-arrows (5x steps) toward the left front corner of the floor
    await reset(page);
    for (const k of ['Shift+ArrowLeft', 'Shift+ArrowLeft', 'Shift+ArrowDown', 'Shift+ArrowDown']) await page.keyboard.press(k);
    const tilted = await pool(page);
    log(`tilted aim: [${tilted.d.map((x) => x.toFixed(3))}]`);
    await run(page, 'ArrowUp', [0, -1], 'tilted aim, ↑');
    await run(page, 'ArrowRight', [1, 0], 'tilted aim, →');
    await run(page, 'ArrowDown', [0, 1], 'tilted aim, ↓');
    await run(page, 'ArrowLeft', [-1, 0], 'tilted aim, ←');

    await keysInOneTask(page, ['ArrowUp', '0'], '↑ then 0 in one task');
    await keysInOneTask(page, ['0', 'ArrowUp'], '0 then ↑ in one task');
    await keysInOneTask(page, ['ArrowLeft', 'ArrowLeft', '0', 'ArrowDown'], '← ← 0 ↓ in one task');

    check(page.problems.length === 0, `no console errors${page.problems.length ? `:\n  ${page.problems.join('\n  ')}` : ''}`);
    await daemon.stop();
}

H.run(main);
