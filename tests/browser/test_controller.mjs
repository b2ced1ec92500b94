// test_controller.mjs -- the frame-time controller in the browser (issue 13), against a real
// `iird serve` on the built-in Cornell box: the Stats panel says "off" until target_fps is set in
// the method panel; with a target every machine reaches (2 fps) and ctl_vpls_max 64, a drag of the
// spot gives the controller interactive frames, and the panel shows the rate it holds against the
// target, its N (64: the most it may use) and the narrower interleave it climbs to with the time to
// spare, while the stats' VPL set holds that N; target_fps 0 turns it off again. What is tested is
// the path through the panel, the protocol, the daemon and the method, not the machine's speed (the
// controller's convergence is test_controller's, its timing docs/experiments.md's).
// Screenshot: browser_controller.png in $IIR_TEST_TMP (harness shotPath).
//
// Usage (as ctest runs it): node tests/browser/test_controller.mjs IIRD SOURCE_DIR

import path from 'node:path';
import * as H from './harness.mjs';

const [IIRD, SRC] = process.argv.slice(2);
const { check, log } = H;

// A shift-drag of the spot across the image and back, `moves` moves: interactive frames.
const drag = (page, moves) => H.shiftDrag(page, { moves, amp: 0.2, turns: moves / 40, delayMs: 40 });

const ctlText = (page) => page.locator('#st-ctl').textContent();

async function main() {
    const { daemon, page } = await H.openSmallSession(IIRD, SRC);
    check((await ctlText(page)) === 'off', `the controller shows off without a target: ${await ctlText(page)}`);

    await H.setParam(page, 'ctl_vpls_max', 64);
    await H.setParam(page, 'target_fps', 2);
    let text = '';
    for (let round = 0; round < 12 && !/N 64 · n 2 ·/.test(text); round++) {
        await drag(page, 40);
        await H.settle(page, 1);
        text = await ctlText(page);
        log(`after drag ${round + 1}: controller ${text}`);
    }
    check(/^\d+\/2 fps · N 64 · n 2 · \d+²$/.test(text), `the controller holds its target with N 64 and interleave 2: ${text}`);
    const count = await page.evaluate(() => window.iir.vplChart.filter((r) => r[1] !== null).at(-1)[1]);
    // the set follows the controller's N (not vpls' 256); a frame of the drag may end a few VPLs
    // short of it, the ones the moving spot killed that frame beyond what it refilled
    check(count <= 64 && count >= 0.9 * 64, `the VPL set holds the controller's N, 64: ${count}`);
    await page.screenshot({ path: H.shotPath('browser_controller.png') });

    await H.setParam(page, 'target_fps', 0);
    await drag(page, 5);
    await H.settle(page, 1);
    check((await ctlText(page)) === 'off', `target_fps 0 turns it off: ${await ctlText(page)}`);
    check(page.problems.length === 0, `no console errors${page.problems.length ? `:\n  ${page.problems.join('\n  ')}` : ''}`);
    await daemon.stop();
}

H.run(main);
