// test_tabs.mjs -- a user's own tabs are not held by a limit meant for strangers (issue 26, item 9):
// with --max-sessions 4 and the default per-address limit (max(1, 4 / 4) = 1 for remote clients),
// four tabs of one browser on this machine each open a session, draw frames of their own and answer a light move
// in their own session, and their images are in colour (the screenshots are checked). A fifth tab
// beyond --max-sessions 4 is refused with the daemon's "full" message in its image area.
// Screenshots: tabs_<i>.png, tabs_full.png in $IIR_TEST_TMP (harness shotPath).
//
// Usage (as ctest runs it): node tests/browser/test_tabs.mjs IIRD SOURCE_DIR

import path from 'node:path';
import * as H from './harness.mjs';

const [IIRD, SRC] = process.argv.slice(2);
const { check, log } = H;

const TABS = 4;

// A tab's image is in colour: the Cornell box reads saturation 20+, a greyed or black frame ~0.
async function inColour(page, label, shot) {
    const t = H.tone(await H.screenRGB(page, '#frame', 128, 96, shot));
    check(t.sat > 4 && t.lum > 5, `${label}: the image is in colour (saturation ${t.sat.toFixed(1)}, brightness ${t.lum.toFixed(1)})`);
}

async function main() {
    const chromium = await H.prerequisites(IIRD, SRC);
    // No --max-sessions-per-address: the product's default, max(1, 4 / 4) = 1.
    const { daemon, url } = await H.startDaemon(IIRD, [...H.refineArgs(), '--size', '256x192', '--sm-res', '64', '--max-sessions', String(TABS),
        ...H.webArgs(IIRD, path.join(SRC, 'web'))]);
    log(`daemon at ${url} (${daemon.cmd})`);
    const browser = await H.launch(chromium);
    const tabs = [];
    for (let i = 0; i < TABS; i++) {
        const page = await H.newPage(browser);
        await H.open(page, url);
        await H.settle(page, 1);
        tabs.push(page);
        log(`tab ${i + 1}: session open, ${await page.evaluate(() => window.iir.framesDrawn)} frames drawn`);
    }
    for (let i = 0; i < TABS; i++) {
        const page = tabs[i];
        await page.bringToFront();
        const n0 = await page.evaluate(() => window.iir.framesDrawn);
        const s0 = await page.evaluate(() => window.iir.inputSeq);
        await page.focus('#frame');
        await page.keyboard.press('ArrowLeft');
        // the frame that answers the move: a refinement pass of the old view would not do (a
        // session still refining draws those anyway)
        await H.waitFor(page, (s) => window.iir.inputSeq > s && window.iir.lastFrame.seq !== 0xffffffff &&
            window.iir.lastFrame.seq >= window.iir.inputSeq, s0);
        const n1 = await page.evaluate(() => window.iir.framesDrawn);
        check(n1 > n0, `tab ${i + 1}: a light move is answered by its own frames (${n0} -> ${n1})`);
        await inColour(page, `tab ${i + 1}`, H.shotPath(`tabs_${i + 1}.png`));
        check(page.problems.length === 0, `tab ${i + 1}: no errors${page.problems.length ? `:\n  ${page.problems.join('\n  ')}` : ''}`);
    }

    // The daemon's own limit still holds: one tab more than --max-sessions is told the server is full.
    const extra = await H.newPage(browser, { expected: /full|sessions/ });
    await extra.goto(url, { waitUntil: 'load' });
    await H.waitFor(extra, () => /full|sessions open/i.test(document.body.innerText), null, H.WAIT_MS);
    const said = await extra.evaluate(() => document.body.innerText);
    const line = (said.match(/.*(full|sessions open).*/i) || [''])[0].trim();
    log(`tab ${TABS + 1}: "${line}"`);
    check(!/this address/i.test(line), `tab ${TABS + 1}: refused by the daemon's limit, not the per-address one ("${line}")`);
    await extra.screenshot({ path: H.shotPath('tabs_full.png') });
    await daemon.stop();
}

H.run(main);
