// test_controller.mjs -- the frame-time controller in the browser (issues 13 and 26), against a real
// `iird serve` on the built-in Cornell box: the Stats panel says "off" until target_fps is set in
// the method panel.
//  1. Refinement alone is no frame rate: after target_fps is set, while only refinement passes run,
//     the panel has no fps figure ("–/F fps (no interactive frame yet)") and the controller keeps
//     vpls' 256; it shows its floor (ctl_vpls_min 64, ctl_sm_res_min 64).
//  2. With a target every machine reaches (2 fps) and ctl_vpls_max 64, a drag of the spot gives the
//     controller interactive frames, and the panel shows the rate it holds against the target, its
//     N (64: the most it may use) and the narrower interleave it climbs to with the time to spare,
//     while the stats' VPL set holds that N.
//  3. With a target no machine reaches (1000 fps) and the ceiling back at 1024, dragging never
//     takes the set below the floor (every frame's stats and the VPL chart), the panel says why it
//     misses (unreachable at the floor, or busy), and the screenshot taken mid-drag shows the box
//     (red and green walls, a lit floor) as its refined frame does.
//  4. target_fps 0 brings back the user's settings at once, without a drag: "off" and a set of 256.
// What is tested is the path through the panel, the protocol, the daemon and the method, not the
// machine's speed (the controller's convergence and its busy rule are test_controller's, its
// timing docs/experiments.md's).
// Screenshots: browser_controller.png (2) and browser_controller_floor.png (3) in $IIR_TEST_TMP
// (harness shotPath).
//
// Usage (as ctest runs it): node tests/browser/test_controller.mjs IIRD SOURCE_DIR

import * as H from './harness.mjs';

const [IIRD, SRC] = process.argv.slice(2);
const { check, log } = H;

// A shift-drag of the spot across the image and back, `moves` moves: interactive frames.
const drag = (page, moves) => H.shiftDrag(page, { moves, amp: 0.2, turns: moves / 40, delayMs: 40 });

const ctlText = (page) => page.locator('#st-ctl').textContent();
const FLOOR = 'floor N 64 · 64²';

// Collects, in the page, the controller's N of every frame shown (stats.ctl.vpls) until stopped.
async function watchCtl(page) {
    await page.evaluate(() => {
        window.__ctlSeen = [];
        window.__ctlWatch = setInterval(() => {
            const s = window.iir.shownStats;
            if (s && s.ctl && !s.pass) window.__ctlSeen.push(s.ctl.vpls);
        }, 15);
    });
    return () => page.evaluate(() => (clearInterval(window.__ctlWatch), window.__ctlSeen));
}

// Mean RGB of a box (fractions of the image) in a w x h RGB array.
function meanRGB(rgb, w, h, [x0, y0, x1, y1]) {
    const m = [0, 0, 0];
    let n = 0;
    for (let y = Math.floor(y0 * h); y < Math.floor(y1 * h); y++) {
        for (let x = Math.floor(x0 * w); x < Math.floor(x1 * w); x++) {
            for (let c = 0; c < 3; c++) m[c] += rgb[3 * (y * w + x) + c];
            n++;
        }
    }
    return m.map((v) => v / n);
}

// 1: the figure while only refinement passes run.
async function refinementOnly(page) {
    await H.setParam(page, 'target_fps', 20);
    await H.waitFor(page, () => window.iir.lastFrame.pass >= 4);
    await H.sleep(500);
    const text = await ctlText(page);
    log(`refinement only (pass ${await page.evaluate(() => window.iir.lastFrame.pass)}): controller ${text}`);
    check(/^–\/20 fps \(no interactive frame yet\) · N 256 · n 4 · 64² · /.test(text), `no fps figure before an interactive frame, N still 256: ${text}`);
    check(text.endsWith(FLOOR), `the panel shows the floor (${FLOOR}): ${text}`);
}

// 2: a reachable target: the most VPLs it may use and a narrower interleave.
async function climbs(page) {
    await H.setParam(page, 'ctl_vpls_max', 64);
    await H.setParam(page, 'target_fps', 2);
    let text = '';
    for (let round = 0; round < 12 && !/N 64 · n 2 ·/.test(text); round++) {
        await drag(page, 40);
        await H.settle(page, 1);
        text = await ctlText(page);
        log(`after drag ${round + 1}: controller ${text}`);
    }
    check(new RegExp(`^\\d+/2 fps · N 64 · n 2 · \\d+² · ${FLOOR}$`).test(text), `the controller holds its target with N 64 and interleave 2: ${text}`);
    // the set follows the controller's N (not vpls' 256): no frame of the last drag holds more than
    // 64, and the set is refilled to it. A single frame may end short of it by the VPLs the moving
    // spot killed that frame beyond what kmax refilled -- how many depends on how far the spot
    // jumped between two frames, which a loaded machine makes longer (seen: 55 and 56 beside
    // browser_arrow_tilt) -- so the refill is judged over the last frames, not the last one.
    const all = await page.evaluate(() => window.iir.vplChart.filter((r) => r[1] !== null).map((r) => r[1]));
    const since = all.slice(all.findLastIndex((n) => n > 64) + 1); /* since the set shrank to N */
    const most = Math.max(...since);
    check(since.length >= 5 && most >= 0.9 * 64, `the VPL set holds the controller's N, 64, over ${since.length} frames since it left ${all.find((n) => n > 64) ?? 'vpls'}: ${since.slice(-12).join(', ')}`);
    await page.screenshot({ path: H.shotPath('browser_controller.png') });
}

// 3: an unreachable target: never below the floor while dragging; the mid-drag frame checked.
async function floorHeld(page) {
    await H.setParam(page, 'ctl_vpls_max', 1024);
    await H.setParam(page, 'target_fps', 1000);
    const stop = await watchCtl(page);
    for (let round = 0; round < 2; round++) await drag(page, 40);
    await drag(page, 20);
    await H.settle(page, 0, 100); // the frame answering the last move, before refinement
    const shown = await page.evaluate(() => window.iir.shownStats);
    const text = await ctlText(page);
    const shot = H.shotPath('browser_controller_floor.png');
    const box = await page.locator('#frame').boundingBox();
    const mid = await H.screenRGB(page, '#frame', 64, 48, shot);
    const seen = await stop();
    const counts = await page.evaluate(() => window.iir.vplChart.map((r) => r[1]).filter((c) => c !== null));
    log(`floor: ${text}; N of the frames shown ${Math.min(...seen)}..${Math.max(...seen)} (${seen.length} looks), set ${Math.min(...counts)}..${Math.max(...counts)}; screenshot ${shot} (${box.width.toFixed(0)}x${box.height.toFixed(0)}, frame pass ${shown.pass})`);
    check(seen.length > 10 && Math.min(...seen) >= 64, `the controller never chose fewer than 64 VPLs while dragging: min ${Math.min(...seen)}`);
    // a frame of the drag may end some VPLs short of its N: those the moving spot killed that
    // frame beyond what it refilled (the old controller's sets went down to 16)
    check(Math.min(...counts) >= 0.75 * 64, `no frame's set fell far below the floor: min ${Math.min(...counts)}`);
    check(/^\d+\/1000 fps \((unreachable at the floor|busy: fewer VPLs bought no time)\) · N \d+ · n 4 · 64² · /.test(text) && text.endsWith(FLOOR), `the panel says why it misses and shows the floor: ${text}`);
    check(shown.pass === 0 && shown.ctl.vpls >= 64, `the screenshot is an interactive frame at N >= 64: pass ${shown.pass}, N ${shown.ctl.vpls}`);
    // the box as the eye sees it: the red wall left, the green wall right, the lit floor
    const red = meanRGB(mid, 64, 48, [0.2, 0.4, 0.27, 0.8]);
    const green = meanRGB(mid, 64, 48, [0.73, 0.4, 0.8, 0.8]);
    const floor = meanRGB(mid, 64, 48, [0.3, 0.9, 0.45, 0.97]);
    log(`mid-drag frame: red wall ${red.map((v) => v.toFixed(0))}, green wall ${green.map((v) => v.toFixed(0))}, floor ${floor.map((v) => v.toFixed(0))}`);
    check(red[0] > 1.5 * red[1] && red[0] > 30, `the left wall is red: ${red.map((v) => v.toFixed(0))}`);
    check(green[1] > 1.3 * green[0] && green[1] > 30, `the right wall is green: ${green.map((v) => v.toFixed(0))}`);
    check(floor[0] + floor[1] + floor[2] > 90, `the floor is lit: ${floor.map((v) => v.toFixed(0))}`);
    // and as its refinement shows the same pose (nothing black, greyed or of another pose)
    await H.waitFor(page, () => window.iir.lastFrame.pass >= 8);
    const refined = await H.screenRGB(page, '#frame', 64, 48);
    const d = H.mad(mid, refined);
    check(d < 8, `the mid-drag frame is the refined frame's picture (mean difference ${d.toFixed(2)} of 255)`);
}

// 4: target_fps 0 restores vpls 256 in the next frame, with no drag.
async function restores(page) {
    await H.setParam(page, 'target_fps', 0);
    await H.settle(page, 1);
    const text = await ctlText(page);
    const count = await page.evaluate(() => window.iir.shownStats.vpl.count);
    log(`target_fps 0, no drag: controller ${text}, set ${count}`);
    check(text === 'off', `target_fps 0 turns it off: ${text}`);
    check(count === 256, `the set is back at vpls 256 without a drag: ${count}`);
}

async function main() {
    const { daemon, page } = await H.openSmallSession(IIRD, SRC, { refinePasses: 16 }); // its refined frame: pass 8
    check((await ctlText(page)) === 'off', `the controller shows off without a target: ${await ctlText(page)}`);
    await refinementOnly(page);
    await climbs(page);
    await floorHeld(page);
    await restores(page);
    check(page.problems.length === 0, `no console errors${page.problems.length ? `:\n  ${page.problems.join('\n  ')}` : ''}`);
    await daemon.stop();
}

H.run(main);
