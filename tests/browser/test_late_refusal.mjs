// test_late_refusal.mjs -- a method the session takes and then cannot render (issue 26, item 3):
// radiosity on the conference room (331179 triangles; radiosity takes at most 200000 patches) is
// refused by the session's worker after the `state` of the switch, as an `error` of the same seq.
// The page must not keep "rendering the first frame…" over the greyed image: the image area says
// that radiosity cannot render conference, the server's reason and what would work (buttons), and
// the parameters banner is in sight even with the panel scrolled to its end.
//  1. on conference with iir, the method radiosity: the refusal in the image area, iir used again
//     (the page asks for it back), conference's frames in colour under it; the banner visible;
//  2. on the built-in box with radiosity, the scene conference: the refusal in the image area with
//     other methods and "back to builtin" as buttons; "use iir" then shows conference with iir.
// Screenshots: late_refusal_method.png, late_refusal_scene.png (the image area) in $IIR_TEST_TMP
// (harness shotPath).
//
// Usage (as ctest runs it): node tests/browser/test_late_refusal.mjs IIRD SOURCE_DIR

import path from 'node:path';
import * as H from './harness.mjs';

const [IIRD, SRC] = process.argv.slice(2);
const { check, log } = H;

const GREY_SAT_MAX = 4;

const pick = (page, selector, value) => page.evaluate(({ selector, value }) => {
    const sel = document.querySelector(selector);
    sel.value = value;
    sel.dispatchEvent(new Event('change'));
}, { selector, value });

async function firstFrameOf(page, scene, method, timeout = 4 * H.WAIT_MS) {
    await H.waitFor(page, ({ scene, method }) => {
        const s = window.iir.state;
        return s.scene === scene && s.params.method === method && !window.iir.switching && !window.iir.greyed &&
            window.iir.lastFrame.generation >= window.iir.generation;
    }, { scene, method }, timeout);
}

// The curtain box is on screen over the image area, and says `title` (regex) and the reason.
async function refusalShown(page, label, title, shot) {
    await H.waitFor(page, () => window.iir.curtain.mode === 'refused', null, 4 * H.WAIT_MS);
    const c = await page.evaluate(() => window.iir.curtain);
    log(`${label}: curtain "${c.title}" / "${c.text}"`);
    check(title.test(c.title) && /200000 patches/.test(c.text), `${label}: the image area says "${c.title}" and why ("${c.text.slice(0, 90)}…")`);
    const buttons = await page.locator('#curtain-actions button').allTextContents();
    check(buttons.length > 0, `${label}: with what would work: ${buttons.join(' | ')}`);
    check(await page.locator('#curtain .curtain-box').isVisible(), `${label}: the refusal box is visible`);
    // the screenshot of the image area holds the box's text: light pixels over its dark box
    const box = await page.locator('#curtain .curtain-box').boundingBox();
    const vp = await page.locator('#viewport').boundingBox();
    check(box && box.x >= vp.x - 1 && box.y >= vp.y - 1 && box.x + box.width <= vp.x + vp.width + 1 && box.y + box.height <= vp.y + vp.height + 1,
        `${label}: the box lies inside the image area`);
    const rgb = await H.screenRGB(page, '#curtain .curtain-box', Math.round(box.width), Math.round(box.height));
    let light = 0;
    for (let i = 0; i < rgb.length; i += 3) if ((rgb[i] + rgb[i + 1] + rgb[i + 2]) / 3 > 100) light++;
    // text over the box's dark grey: measured ~4800 of ~69000 pixels (title, reason, buttons)
    check(light > 200, `${label}: the box's text is on the screenshot (${light} light pixels of ${rgb.length / 3})`);
    await H.screenRGB(page, '#viewport', 128, 96, shot);
    await H.sleep(3000);
    const later = await page.evaluate(() => window.iir.curtain);
    check(later.mode === 'refused' && !/rendering the first frame/.test(later.title), `${label}: 3 s later it still says so (not "rendering the first frame…")`);
    return buttons;
}

async function bannerInSight(page, label) {
    await page.evaluate(() => (document.querySelector('#panel').scrollTop = 1e6));
    await H.sleep(200);
    const b = page.locator('.error[data-kind="params"], .error[data-kind="scene"]').first();
    const ok = (await b.count()) > 0 && (await b.isVisible());
    const inView = ok && (await page.evaluate(() => {
        const e = document.querySelector('.error[data-kind="params"], .error[data-kind="scene"]');
        const r = e.getBoundingClientRect();
        const p = document.querySelector('#panel').getBoundingClientRect();
        const under = document.elementFromPoint(r.left + 5, r.top + r.height / 2);
        return r.top >= p.top && r.bottom <= p.bottom && r.height > 0 && !!under && e.contains(under);
    }));
    check(ok && inView, `${label}: the banner is in sight with the panel scrolled to its end (${ok ? await b.textContent() : 'none'})`);
    await page.evaluate(() => (document.querySelector('#panel').scrollTop = 0));
}

async function main() {
    const chromium = await H.prerequisites(IIRD, SRC);
    const scenes = H.makeScenes(SRC, { conference: true });
    const { daemon, url } = await H.startDaemon(IIRD, [...H.refineArgs(), '--scenes', scenes, '--size', '256x192', '--sm-res', '64', ...H.webArgs(IIRD, path.join(SRC, 'web'))]);
    log(`daemon at ${url} (${daemon.cmd})`);
    const browser = await H.launch(chromium);
    const page = await H.newPage(browser, { expected: /\[unsupported\]|200000 patches/ });
    await H.recordWire(page);
    await H.open(page, url);
    await H.settle(page, 1);

    // 1. conference with iir, then radiosity
    await pick(page, '#scene', 'conference');
    await firstFrameOf(page, 'conference', 'iir');
    await pick(page, '#param-method', 'radiosity');
    await refusalShown(page, 'radiosity on conference', /radiosity cannot render conference/, H.shotPath('late_refusal_method.png'));
    await firstFrameOf(page, 'conference', 'iir');
    const t = H.tone(await H.screenRGB(page, '#frame', 128, 96));
    check(!(await page.evaluate(() => window.iir.greyed)) && t.sat > GREY_SAT_MAX,
        `radiosity on conference: iir is used again and its frames are on screen in colour (saturation ${t.sat.toFixed(1)})`);
    check((await page.evaluate(() => document.querySelector('#param-method').value)) === 'iir', 'the method picker says iir');
    await bannerInSight(page, 'radiosity on conference');
    await page.click('#curtain-close');

    // 2. the built-in box with radiosity, then conference
    await pick(page, '#scene', 'builtin');
    await firstFrameOf(page, 'builtin', 'iir');
    await pick(page, '#param-method', 'radiosity');
    await firstFrameOf(page, 'builtin', 'radiosity');
    await pick(page, '#scene', 'conference');
    const buttons = await refusalShown(page, 'conference with radiosity', /radiosity cannot render conference/, H.shotPath('late_refusal_scene.png'));
    check(buttons.includes('back to builtin') && buttons.includes('use iir'), 'the buttons offer other methods and the scene before');
    await bannerInSight(page, 'conference with radiosity');
    await page.locator('#curtain-actions button', { hasText: 'use iir' }).click();
    await firstFrameOf(page, 'conference', 'iir');
    const c = await page.evaluate(() => window.iir.curtain);
    check(c.mode === 'none', `"use iir" shows conference with iir, curtain gone (${c.mode})`);

    check(page.problems.length === 0, `no console errors${page.problems.length ? `:\n  ${page.problems.join('\n  ')}` : ''}`);
    await daemon.stop();
}

H.run(main);
