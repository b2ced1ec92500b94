// issue16_shots.mjs -- the before/after screenshots of issue 16's note: the same two user actions
// against the old product and the current one, each in headless Chromium (playwright-core, as the
// browser tests):
//   wall-drag      the built-in Cornell box, shift-drag across 30% of the image towards the red wall
//   scene-switch   picking point_box (a scene whose only light is a point light: iir cannot render it)
// Writes OUT/{before,after}-{wall-drag,scene-switch}.png (full page: image and panel) and prints what
// each page showed (light position, picker, error, image-area text).
//
// Usage: node tools/issue16_shots.mjs [--after IIRD] [--before IIRD] [--before-web DIR] [--out DIR]
//   defaults: --after build/iird (else build-asan/iird), --before /tmp/iird-before,
//             --before-web /tmp/before/web, --out out/issue16. `--before none` takes only the after set.

import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import * as H from '../tests/browser/harness.mjs';

const SRC = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');

function args() {
    const a = { before: '/tmp/iird-before', beforeWeb: '/tmp/before/web', out: path.join(SRC, 'out', 'issue16') };
    const argv = process.argv.slice(2);
    for (let i = 0; i < argv.length; i += 2) {
        const [k, v] = [argv[i], argv[i + 1]];
        if (k === '--after') a.after = v;
        else if (k === '--before') a.before = v;
        else if (k === '--before-web') a.beforeWeb = v;
        else if (k === '--out') a.out = path.resolve(v);
        else throw new Error(`unknown option ${k} (see the usage at the top of ${path.basename(process.argv[1])})`);
    }
    a.after = a.after || ['build/iird', 'build-asan/iird', 'build-h4/iird'].map((p) => path.join(SRC, p)).find((p) => fs.existsSync(p));
    if (!a.after) throw new Error('no iird found in build/ or build-asan/: build it, or give --after IIRD');
    return a;
}

// What the page says about itself, from the DOM only (the old client has no window.iir.state).
const pageSays = (page) => page.evaluate(() => {
    const text = (sel) => {
        const e = document.querySelector(sel);
        return e && !e.closest('[hidden]') && e.offsetParent !== null ? e.textContent.trim().replace(/\s+/g, ' ') : null;
    };
    return {
        scene: document.querySelector('#scene').value,
        light: text('#light-pos'),
        error: text('#errors') || text('#error'),
        imageArea: text('#curtain'),
        frame: text('#hud-frame'),
    };
});

async function shots(chromium, label, iird, web, scenes, out) {
    const { daemon, url } = await H.startDaemon(iird, ['--scenes', scenes, ...H.webArgs(iird, web)]);
    const browser = await H.launch(chromium);
    try {
        // wall-drag
        let page = await H.newPage(browser);
        await H.open(page, url);
        await H.sleep(2500);
        const box = await page.locator('#frame').boundingBox();
        const y = box.y + box.height * 0.5;
        await page.keyboard.down('Shift');
        await page.mouse.move(box.x + box.width * 0.5, y);
        await page.mouse.down();
        await page.mouse.move(box.x + box.width * 0.2, y, { steps: 15 });
        await H.sleep(200);
        await page.mouse.up();
        await page.keyboard.up('Shift');
        await H.sleep(3000);
        let file = path.join(out, `${label}-wall-drag.png`);
        await page.screenshot({ path: file });
        H.log(`${file}: ${JSON.stringify(await pageSays(page))}`);
        await page.close();

        // scene-switch
        page = await H.newPage(browser);
        await H.open(page, url);
        await H.sleep(2500);
        await page.selectOption('#scene', 'point_box');
        await H.sleep(2500);
        file = path.join(out, `${label}-scene-switch.png`);
        await page.screenshot({ path: file });
        H.log(`${file}: ${JSON.stringify(await pageSays(page))}`);
        await page.close();
    } finally {
        await browser.close();
        await daemon.stop();
    }
}

// The old client's folder as served: uPlot is not in git (make web-deps copies it into web/vendor/),
// so a checkout without it gets a copy with this tree's vendor/ (removed at exit).
function servable(web) {
    if (fs.existsSync(path.join(web, 'vendor', 'uplot', 'uPlot.esm.js'))) return web;
    const tmp = fs.mkdtempSync(path.join(process.env.IIR_TEST_TMP || '/tmp', 'iir-before-web-'));
    H.onCleanup(() => fs.rmSync(tmp, { recursive: true, force: true }));
    fs.cpSync(web, tmp, { recursive: true });
    fs.cpSync(path.join(SRC, 'web', 'vendor'), path.join(tmp, 'vendor'), { recursive: true });
    return tmp;
}

H.run(async () => {
    const a = args();
    const chromium = await H.prerequisites(a.after, SRC);
    fs.mkdirSync(a.out, { recursive: true });
    const scenes = H.makeScenes(SRC);
    if (a.before !== 'none') {
        if (!fs.existsSync(a.before) || !fs.existsSync(a.beforeWeb)) throw new Error(`${a.before} or ${a.beforeWeb} is missing (or give --before none)`);
        await shots(chromium, 'before', a.before, servable(a.beforeWeb), scenes, a.out);
    }
    await shots(chromium, 'after', a.after, path.join(SRC, 'web'), scenes, a.out);
});
