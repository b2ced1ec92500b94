// ctl_drag.mjs -- where the frame-time controller settles while a user drags the spot (issue 26,
// item 6): `iird serve` on the built-in Cornell box at its default frame size, target_fps F set in
// the method panel, a few seconds of refinement alone (what the panel's figure reads then), then
// shift-drags of the spot (40 moves 40 ms apart each), printing the panel's controller read-out and
// the frame's set after each; a full-page screenshot (image and panel) mid-drag; then target_fps 0
// and what the set holds without a drag. Headless Chromium through playwright-core, as the browser
// tests (tests/browser/harness.mjs).
//
// Usage: node tools/ctl_drag.mjs IIRD SOURCE_DIR SHOT.png [--fps F] [--drags K]
//   SOURCE_DIR: where web/ and node_modules/ are (an old checkout for a "before"); F 20, K 8.

import path from 'node:path';
import * as H from '../tests/browser/harness.mjs';

const args = process.argv.slice(2);
const opt = (name, def) => (args.includes(name) ? Number(args[args.indexOf(name) + 1]) : def);
const [IIRD, SRC, SHOT] = args;
const FPS = opt('--fps', 20);
const DRAGS = opt('--drags', 8);

const ctl = (page) => page.locator('#st-ctl').textContent();

// The stats of the frame on screen (a moment after a switch there may be none yet).
async function stats(page) {
    for (let i = 0; i < 50; i++) {
        const s = await page.evaluate(() => window.iir.shownStats || window.iir.lastStats);
        if (s) return s;
        await H.sleep(100);
    }
    return {};
}

async function main() {
    const chromium = await H.prerequisites(IIRD, SRC);
    const { daemon, url } = await H.startDaemon(IIRD, H.webArgs(IIRD, path.join(SRC, 'web')));
    const browser = await H.launch(chromium);
    const page = await H.newPage(browser);
    await H.open(page, url);
    await H.settle(page, 1);
    await H.setParam(page, 'target_fps', FPS);
    await H.sleep(4000);
    const pass = await page.evaluate(() => window.iir.lastFrame.pass);
    H.log(`before any drag (refinement only, last frame pass ${pass}): ${await ctl(page)}`);
    const Ns = [];
    for (let round = 0; round < DRAGS; round++) {
        await H.shiftDrag(page, { moves: 40, amp: 0.2, turns: 1, delayMs: 40 });
        const s = await stats(page);
        H.log(`drag ${round + 1}: ${await ctl(page)} | frame ${s.total_ms} ms, set ${s.vpl && s.vpl.count}`);
        if (s.ctl) Ns.push(s.ctl.vpls);
    }
    await H.shiftDrag(page, { moves: 20, amp: 0.2, turns: 0.5, delayMs: 40 });
    await page.evaluate(() => document.querySelector('#st-ctl').closest('details').scrollIntoView({ block: 'start', inline: 'nearest' }));
    await page.screenshot({ path: SHOT });
    H.log(`screenshot ${SHOT}: ${await ctl(page)}`);
    H.log(`N after each drag: ${Ns.join(', ')}`);
    await H.setParam(page, 'target_fps', 0);
    await H.sleep(1500);
    const s = await stats(page);
    H.log(`after target_fps 0 (no move): controller ${await ctl(page)}, set ${s.vpl && s.vpl.count}`);
    await daemon.stop();
}

H.run(main);
