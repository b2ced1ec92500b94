// test_notes.mjs -- what the method leaves out of the scene is said, not silently dropped (issue 16),
// against a real `iird serve` with glow_box (the Cornell box with a spot and its ceiling lamp emitting):
//  1. the built-in box under iir has no notice;
//  2. glow_box under iir: a notice (not an error) names the lamp's material 'light' and says its
//     indirect light is left out (state.notes); screenshot browser_notes.png;
//  3. pt renders every light: the notice goes; back on iir it comes again;
//  4. it can be dismissed, and stays away while the notes do not change (an exposure change);
//  5. pt on cornell_spheres at its default 2 bounces shows the glass sphere black: a notice (a
//     warning in state.notes) names the material 'glass' and says bounces 3 shows light through it;
//     at bounces 4 the notice goes and the sphere is lit (its pixels measured on the frame,
//     screenshots browser_notes_glass_b2.png and browser_notes_glass_b4.png; issue 26, item 11a);
//  6. rsm on cornell_spheres says it renders the mirror and the glass black, and draws no VPL dot over
//     them (VPLs there carry no light; overlay pixels of a dot's colours counted inside the spheres'
//     outlines, screenshot browser_notes_rsm_dots.png; issue 26, item 11d).
//
// Usage (as ctest runs it): node tests/browser/test_notes.mjs IIRD SOURCE_DIR

import fs from 'node:fs';
import path from 'node:path';
import * as H from './harness.mjs';

const [IIRD, SRC] = process.argv.slice(2);
const { check, log } = H;

const notice = (page) => page.evaluate(() => {
    const el = document.querySelector('#errors [data-kind="notes"]');
    return el ? { text: el.textContent, note: el.classList.contains('note') } : null;
});

// Measured (RelWithDebInfo, 2 cores, exposure +0.5 from step 4): the glass sphere's middle is 5.2 (0-255)
// at bounces 2 (a faint Fresnel reflection) and 96 at bounces 4.
const GLASS_DARK = 25;
const GLASS_LIT = 40;
const GLASS = [0.42, 0.33, 0.3]; // the glass sphere's centre (cornell_spheres.obj), radius 0.33
const MIRROR = [-0.42, 0.33, -0.38]; // the mirror sphere's
const SPHERE_R = 0.33;

// Mean brightness (0-255) of the frame within 12% of its height around the glass sphere's middle.
async function glassBrightness(page) {
    const { cam, w, h } = await page.evaluate(() => {
        const f = document.getElementById('frame');
        return { cam: window.iir.state.camera, w: f.width, h: f.height };
    });
    const c = H.project(cam, w, h, GLASS);
    const rgb = await H.canvasRGB(page, 'frame', w, h);
    const r = 0.12 * h;
    let sum = 0;
    let n = 0;
    for (let y = Math.floor(c.y - r); y <= c.y + r; y++) {
        for (let x = Math.floor(c.x - r); x <= c.x + r; x++) {
            if ((x - c.x) ** 2 + (y - c.y) ** 2 > r * r || x < 0 || y < 0 || x >= w || y >= h) continue;
            const k = 3 * (y * w + x);
            sum += (rgb[k] + rgb[k + 1] + rgb[k + 2]) / 3;
            n++;
        }
    }
    return sum / n;
}

// 5: pt on cornell_spheres, 2 bounces then 4.
async function glassHint(page) {
    await page.selectOption('#param-method', 'pt'); // first: the spheres load straight into pt
    await H.waitFor(page, () => window.iir.state.params.method === 'pt' && !window.iir.switching);
    await page.selectOption('#scene', 'cornell_spheres');
    await H.waitFor(page, () => window.iir.state.scene === 'cornell_spheres' && !window.iir.switching &&
        !!document.querySelector('#errors [data-kind="notes"]'));
    await H.settle(page, 2);
    const n = await notice(page);
    const dark = await glassBrightness(page);
    await page.screenshot({ path: H.shotPath('browser_notes_glass_b2.png') });
    log(`pt at bounces ${await page.evaluate(() => window.iir.state.params.bounces)}: glass ${dark.toFixed(1)}; notice: ${n && n.text}`);
    check(n && /material 'glass'/.test(n.text) && /bounces 3 shows/.test(n.text) && dark < GLASS_DARK,
        `pt at 2 bounces: the glass sphere is black (${dark.toFixed(1)} < ${GLASS_DARK}) and a notice says bounces 3 shows light through it`);
    await H.setParam(page, 'bounces', 4);
    await H.waitFor(page, () => !document.querySelector('#errors [data-kind="notes"]'));
    await H.settle(page, 2);
    const lit = await glassBrightness(page);
    await page.screenshot({ path: H.shotPath('browser_notes_glass_b4.png') });
    check(lit > GLASS_LIT, `at bounces 4 the notice goes and the glass sphere is lit: ${lit.toFixed(1)} > ${GLASS_LIT}`);
}

// Overlay pixels of a VPL dot's colours (view.js drawVpls) inside the spheres' outlines (shrunk by
// 10%), and the dots the page drew in all.
async function dotsOverSpheres(page) {
    const { cam, w, h } = await page.evaluate(() => {
        const f = document.getElementById('frame');
        return { cam: window.iir.state.camera, w: f.width, h: f.height };
    });
    const circles = [GLASS, MIRROR].map((c) => {
        const p = H.project(cam, w, h, c);
        const dist = Math.hypot(...c.map((x, i) => x - cam.position[i]));
        const r = (0.9 * SPHERE_R / dist) / Math.tan((cam.fov * Math.PI) / 360) * (h / 2);
        return { x: p.x, y: p.y, r };
    });
    const over = await page.evaluate(({ circles, w }) => {
        const o = document.getElementById('overlay');
        const s = o.width / w;
        const d = o.getContext('2d').getImageData(0, 0, o.width, o.height).data;
        const colours = [[255, 200, 60], [80, 255, 140], [70, 140, 255], [120, 220, 255]];
        let n = 0;
        for (let y = 0; y < o.height; y++) {
            for (let x = 0; x < o.width; x++) {
                if (!circles.some((c) => (x / s - c.x) ** 2 + (y / s - c.y) ** 2 < c.r * c.r)) continue;
                const k = 4 * (y * o.width + x);
                if (d[k + 3] < 150) continue;
                if (colours.some((c) => Math.abs(d[k] - c[0]) + Math.abs(d[k + 1] - c[1]) + Math.abs(d[k + 2] - c[2]) < 45)) n++;
            }
        }
        return n;
    }, { circles, w });
    return { over, drawn: await page.evaluate(() => window.iir.vplsDrawn) };
}

// 6: rsm on cornell_spheres: no dots over the black spheres.
async function rsmDots(page) {
    await page.selectOption('#param-method', 'rsm');
    await H.waitFor(page, () => window.iir.state.params.method === 'rsm' && !window.iir.switching);
    await H.settle(page, 2);
    await H.waitFor(page, () => window.iir.vplsDrawn > 0);
    const n = await notice(page);
    const dots = await dotsOverSpheres(page);
    await page.screenshot({ path: H.shotPath('browser_notes_rsm_dots.png') });
    log(`rsm: ${dots.drawn} dots drawn, ${dots.over} dot pixels over the spheres; notice: ${n && n.text}`);
    check(n && /material 'glass'/.test(n.text) && /material 'mirror'/.test(n.text), 'rsm says it renders the mirror and the glass black');
    check(dots.drawn > 0 && dots.over === 0, `and draws no VPL dot over them (${dots.over} pixels; ${dots.drawn} dots elsewhere)`);
}

async function main() {
    const chromium = await H.prerequisites(IIRD, SRC);
    const scenes = H.makeScenes(SRC);
    fs.cpSync(path.join(SRC, 'scenes', 'cornell_spheres'), path.join(scenes, 'cornell_spheres'), { recursive: true });
    const { daemon, url } = await H.startDaemon(IIRD, [...H.refineArgs(), '--scenes', scenes, ...H.webArgs(IIRD, path.join(SRC, 'web'))]);
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
    // everything the daemon sends for the change has arrived: its state (the notes come only in
    // states), then the frame answering it, drawn
    await H.waitFor(page, () => {
        const f = window.iir.lastFrame;
        return f && f.seq !== 0xffffffff && f.seq >= window.iir.inputSeq;
    });
    check(changed && (await notice(page)) === null, `a dismissed notice stays away while the notes do not change (exposure now ${(await page.evaluate(() => window.iir.state.params.exposure))})`);

    await glassHint(page);
    await rsmDots(page);

    check(page.problems.length === 0, `no console errors${page.problems.map((p) => `\n  ${p}`).join('')}`);
    await daemon.stop();
}

H.run(main);
