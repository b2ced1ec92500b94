// test_scene_picks.mjs -- quick scene picks never freeze the page (issue 26, item 1): with the scene
// picker focused, ↓ is pressed through the whole list with no delay, then ↑ back through it ~250 ms
// apart, and ↓ again ~250 ms apart (each press asking for the next scene in the list); each time the page must end showing the last scene asked for: the state names it, the
// picker says it, no switch is pending, the curtain is gone, frames of its generation are drawn and
// the image on screen is in colour (not greyed; the screenshot is checked). Every `scene` sent gets
// its reply (a `state`, `"superseded": true` for one replaced before its load began, or an error).
// Screenshots: scene_picks_fast.png, scene_picks_slow.png in $IIR_TEST_TMP (harness shotPath).
//
// Usage (as ctest runs it): node tests/browser/test_scene_picks.mjs IIRD SOURCE_DIR

import path from 'node:path';
import * as H from './harness.mjs';

const [IIRD, SRC] = process.argv.slice(2);
const { check, log } = H;

// Greyed, the image reads saturation ~0 (test_switch: 0.0-0.13); the box scenes in colour read 20+.
const GREY_SAT_MAX = 4;

// Presses `key` on the focused picker `n` times, `delayMs` apart; returns the names sent.
async function pressThrough(page, key, n, delayMs) {
    await page.focus('#scene');
    for (let i = 0; i < n; i++) {
        await page.keyboard.press(key);
        if (delayMs) await H.sleep(delayMs);
    }
}

async function endsOnLastAsked(page, label, shot) {
    const wire = await page.evaluate(() => window.__wire.filter((m) => m.dir === 'out' && m.type === 'scene').map((m) => ({ seq: m.seq, name: m.name })));
    const last = wire[wire.length - 1];
    const picker = await page.evaluate(() => document.querySelector('#scene').value);
    log(`${label}: ${wire.length} scene messages in all, the last asked for ${last && last.name}, the picker says ${picker}`);
    check(last && picker === last.name, `${label}: the picker says the last scene asked for (${picker})`);
    // a conference load under ASan takes a while: generous
    await H.waitFor(page, (name) => {
        const i = window.iir;
        return i.state.scene === name && !i.switching && !i.greyed && i.curtain.mode === 'none' &&
            i.lastFrame && i.lastFrame.generation >= i.generation;
    }, last.name, 4 * H.WAIT_MS);
    const n0 = await page.evaluate(() => window.iir.framesDrawn);
    await H.waitFor(page, (n) => window.iir.framesDrawn > n || performance.now() - window.iir.lastFrame.drawnAt > 1500, n0);
    const st = await H.pageState(page);
    check(st.scene === last.name && st.curtain.mode === 'none' && !st.greyed,
        `${label}: the page shows ${st.scene}, curtain ${st.curtain.mode}, greyed ${st.greyed}`);
    const rgb = await H.screenRGB(page, '#frame', 128, 96, shot);
    const t = H.tone(rgb);
    check(t.sat > GREY_SAT_MAX && t.lum > 5, `${label}: the image on screen is in colour (saturation ${t.sat.toFixed(1)} > ${GREY_SAT_MAX}, brightness ${t.lum.toFixed(1)})`);
    const replies = await page.evaluate(() => {
        const w = window.__wire;
        return w.filter((m) => m.dir === 'out' && m.type === 'scene')
            .map((o) => ({ seq: o.seq, reply: (w.find((m) => m.dir === 'in' && m.socket === o.socket && m.seq === o.seq && (m.type === 'state' || m.type === 'error')) || {}).type || null }));
    });
    const missing = replies.filter((r) => !r.reply);
    check(missing.length === 0, `${label}: every scene message was answered (${replies.length}; missing: ${JSON.stringify(missing)})`);
}

async function main() {
    const chromium = await H.prerequisites(IIRD, SRC);
    const scenes = H.makeScenes(SRC, { conference: true });
    const { daemon, url } = await H.startDaemon(IIRD, [...H.refineArgs(), '--scenes', scenes, '--size', '256x192', '--sm-res', '64', ...H.webArgs(IIRD, path.join(SRC, 'web'))]);
    log(`daemon at ${url} (${daemon.cmd})`);
    const browser = await H.launch(chromium);
    const page = await H.newPage(browser);
    await H.recordWire(page);
    await H.open(page, url);
    await H.settle(page, 1);
    const names = await page.evaluate(() => [...document.querySelectorAll('#scene option')].map((o) => o.value));
    log(`the picker lists ${names.join(', ')}; shown: ${(await H.pageState(page)).scene}`);

    // 1. no delay, from the top of the list to its end
    await page.selectOption('#scene', names[0]);
    await H.waitFor(page, (n) => window.iir.state.scene === n && !window.iir.switching, names[0], 4 * H.WAIT_MS);
    await pressThrough(page, 'ArrowDown', names.length - 1, 0);
    await endsOnLastAsked(page, 'no delay', H.shotPath('scene_picks_fast.png'));

    // 2. ~250 ms apart, back up to the top
    await pressThrough(page, 'ArrowUp', names.length - 1, 250);
    await endsOnLastAsked(page, '250 ms apart', H.shotPath('scene_picks_slow.png'));
    check((await page.evaluate(() => document.querySelector('#scene').value)) === names[0], `250 ms apart: ↑ through the list ends at its top (${names[0]})`);

    // 3. ~250 ms apart down the list again, conference (a slow load) second: each press asks for the
    // next scene in the list (the picker does not jump back to a scene whose reply came meanwhile)
    const sent0 = await page.evaluate(() => window.__wire.filter((m) => m.dir === 'out' && m.type === 'scene').length);
    await pressThrough(page, 'ArrowDown', names.length - 1, 250);
    const asked = await page.evaluate((n) => window.__wire.filter((m) => m.dir === 'out' && m.type === 'scene').slice(n).map((m) => m.name), sent0);
    check(JSON.stringify(asked) === JSON.stringify(names.slice(1)), `250 ms apart, ↓: each press asked for the next scene in the list: ${asked.join(', ')}`);
    await endsOnLastAsked(page, '250 ms apart, ↓', H.shotPath('scene_picks_slow_down.png'));

    const disc = await H.frameDiscipline(page);
    check(disc.problems.length === 0, `no frame between a switch and its state, none of an older generation (${disc.drawn} frames)${disc.problems.length ? `:\n  ${disc.problems.slice(0, 8).join('\n  ')}` : ''}`);
    check(page.problems.length === 0, `no console errors${page.problems.length ? `:\n  ${page.problems.join('\n  ')}` : ''}`);
    await daemon.stop();
}

H.run(main);
