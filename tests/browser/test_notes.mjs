// test_notes.mjs -- what the method leaves out of the scene is said, not silently dropped (issue 16),
// against a real `iird serve` with glow_box (the Cornell box with a spot and its ceiling lamp emitting):
//  1. the built-in box under iir has no notice;
//  2. glow_box under iir: a notice (not an error) names the lamp's material 'light' and says its
//     indirect light is left out (state.notes); screenshot browser_notes.png;
//  3. pt renders every light: the notice goes; back on iir it comes again;
//  4. it can be dismissed, and stays away while the notes do not change (an exposure change).
//
// Usage (as ctest runs it): node tests/browser/test_notes.mjs IIRD SOURCE_DIR

import path from 'node:path';
import * as H from './harness.mjs';

const [IIRD, SRC] = process.argv.slice(2);
const { check, log } = H;

const notice = (page) => page.evaluate(() => {
    const el = document.querySelector('#errors [data-kind="notes"]');
    return el ? { text: el.textContent, note: el.classList.contains('note') } : null;
});

async function main() {
    const chromium = await H.prerequisites(IIRD, SRC);
    const scenes = H.makeScenes(SRC);
    const { daemon, url } = await H.startDaemon(IIRD, ['--scenes', scenes, ...H.webArgs(IIRD, path.join(SRC, 'web'))]);
    log(`daemon at ${url} (${daemon.cmd})`);
    const browser = await H.launch(chromium);
    const page = await H.newPage(browser);
    await H.open(page, url);
    await H.settle(page);

    check((await notice(page)) === null, 'the built-in box under iir: no notice');

    await page.selectOption('#scene', 'glow_box');
    await H.waitFor(page, () => window.iir.state && window.iir.state.scene === 'glow_box' && !window.iir.switching);
    await H.waitFor(page, () => !!document.querySelector('#errors [data-kind="notes"]'));
    const n = await notice(page);
    log(`notice: ${n && n.text}`);
    check(n && n.note && /material 'light'/.test(n.text) && /indirect/.test(n.text), 'glow_box under iir: a notice names the emitting material whose indirect light iir leaves out');
    await page.screenshot({ path: H.shotPath('browser_notes.png') });

    await page.selectOption('#param-method', 'pt');
    await H.waitFor(page, () => window.iir.state.params.method === 'pt' && !document.querySelector('#errors [data-kind="notes"]'));
    check((await notice(page)) === null, 'pt renders every light: the notice goes');
    await page.selectOption('#param-method', 'iir');
    await H.waitFor(page, () => window.iir.state.params.method === 'iir' && !!document.querySelector('#errors [data-kind="notes"]'));
    check((await notice(page)) !== null, 'back on iir the notice comes again');

    await page.click('#errors [data-kind="notes"] .dismiss');
    check((await notice(page)) === null, 'the notice is dismissed with its × button');
    const gen = await page.evaluate(() => window.iir.generation);
    await page.mouse.move(10, 10);
    await page.keyboard.press('='); // exposure up: a params change that leaves the notes as they were
    const changed = await H.waitFor(page, (g) => window.iir.generation > g, gen).then(() => true, () => false);
    await H.sleep(300);
    check(changed && (await notice(page)) === null, `a dismissed notice stays away while the notes do not change (exposure now ${(await page.evaluate(() => window.iir.state.params.exposure))})`);

    check(page.problems.length === 0, `no console errors${page.problems.map((p) => `\n  ${p}`).join('')}`);
    await daemon.stop();
}

H.run(main);
