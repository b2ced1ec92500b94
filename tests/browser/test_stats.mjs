// test_stats.mjs -- stats that agree with each other (issue 16), against a real `iird serve` on the
// built-in Cornell box:
//  1. one frame counter: the image's overlay, the stats panel and the domain caption name the same
//     frame (the one on screen), on refinement passes too; the VPL read-out is the set's size, never
//     "0/256", and a refinement pass says its set is unchanged;
//  2. the VPL chart has no point for frames without a VPL step, and no "kept" at 0 (a new set has none);
//  3. removed-VPL crosses do not pile up: while aiming, the domain drawing holds at most the removed
//     sites of one frame (its red pixels counted against that), and none once the frame is refined;
//     a re-encoded frame (exposure changed) says "re-encoded" in the image's line and the stats, never
//     "0.0 ms render" (issue 26, item 11e);
//  4. pt: the domain says "pt has no VPL domain" at once and never "no domain from pt yet"; the stats
//     say pt has no VPLs; ir: "ir has no disk domain", its VPL count is the set's size, a new set;
//  5. a method's own counters and phases (issue 27): rsm's panel shows `recomputed`, its stats maps.
// Screenshot: browser_stats.png in $IIR_TEST_TMP (harness shotPath).
//
// Usage (as ctest runs it): node tests/browser/test_stats.mjs IIRD SOURCE_DIR

import path from 'node:path';
import * as H from './harness.mjs';

const [IIRD, SRC] = process.argv.slice(2);
const { check, log } = H;

// A removed site's cross is two 8 px diagonals 1.6 px wide: measured 22 red pixels alone, 26-30 per
// cross over the disk (dark cells and edges under them) at dpr 1; 40 per cross is the bound. With it
// and "crosses drawn <= the removed sites of the domain's frame", crosses left from earlier frames
// (a pile-up) show as more red than the frame's own crosses can make.
const RED_PER_CROSS = 40;

// The three frame numbers on the page, and the VPL read-outs.
function readouts(page) {
    return page.evaluate(() => {
        const num = (sel, re) => {
            const m = re.exec(document.querySelector(sel).textContent);
            return m ? Number(m[1]) : null;
        };
        return {
            hud: num('#hud-frame', /frame (\d+)/),
            stats: num('#st-frame', /^(\d+)/),
            domain: num('#domain-caption', /^frame (\d+)/),
            caption: document.querySelector('#domain-caption').textContent,
            vpls: document.querySelector('#st-vpls').textContent,
            change: document.querySelector('#st-vpl-change').textContent,
            shown: window.iir.lastFrame && { id: window.iir.lastFrame.frameId, pass: window.iir.lastFrame.pass },
            domainFrame: window.iir.lastDomain && window.iir.lastDomain.frame,
            sites: window.iir.lastDomain && window.iir.lastDomain.sites ? window.iir.lastDomain.sites.length : null,
            imageVpls: window.iir.lastDomain && window.iir.lastDomain.vpls ? window.iir.lastDomain.vpls.length : null,
            removed: window.iir.lastDomain && window.iir.lastDomain.removed ? window.iir.lastDomain.removed.length : 0,
            removedDrawn: window.iir.domainRemovedDrawn,
            red: red(),
        };
        // Red (#ff5a5a) pixels of the domain canvas: the removed-site crosses (read in the same task
        // as the numbers above, so of the same drawing).
        function red() {
            const c = document.getElementById('domain');
            const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
            let n = 0;
            for (let i = 0; i < d.length; i += 4) if (d[i] > 200 && d[i + 1] < 130 && d[i + 2] < 130 && d[i + 3] > 150) n++;
            return n;
        }
    });
}

// Waits for a refinement pass on screen and its stats (the session idles into refinement).
async function refined(page) {
    await H.waitFor(page, () => window.iir.lastFrame.pass > 0 && window.iir.shownStats && window.iir.lastDomain);
    await H.sleep(150);
}

function chartProblems(rows) {
    const bad = rows.filter((r) => r[1] === 0 || r[2] === 0 || (r[1] === null && r.slice(2).some((x) => x !== null)));
    return bad.map((r) => JSON.stringify(r));
}

async function main() {
    const chromium = await H.prerequisites(IIRD, SRC);
    const { daemon, url } = await H.startDaemon(IIRD, [...H.refineArgs(), '--scenes', path.join(SRC, 'scenes'), ...H.webArgs(IIRD, path.join(SRC, 'web'))]);
    log(`daemon at ${url} (${daemon.cmd})`);
    const browser = await H.launch(chromium);
    const page = await H.newPage(browser);
    await H.open(page, url);

    // 1. idle: refinement passes
    await refined(page);
    let r = await readouts(page);
    log(`refined: ${JSON.stringify(r)}`);
    check(r.hud === r.shown.id && r.stats === r.shown.id && r.domain === r.shown.id,
        `overlay, stats and domain caption name the frame on screen: ${r.hud}, ${r.stats}, ${r.domain} (frame ${r.shown.id}, pass ${r.shown.pass})`);
    check(new RegExp(`^${r.sites}\\b`).test(r.vpls) && !/^0\//.test(r.vpls), `the stats' VPLs are the set's size, as in the domain: "${r.vpls}" (${r.sites} sites)`);
    check(/unchanged \(pass \d+\)/.test(r.change) && /unchanged/.test(r.caption), `a refinement pass keeps its set: "${r.change}", "${r.caption}"`);
    check(r.removedDrawn === 0 && r.red === 0, 'no removed crosses on a refined frame');
    let rows = await page.evaluate(() => window.iir.vplChart);
    check(rows.some((x) => x[1] > 0) && chartProblems(rows).length === 0, `the VPL chart: points only for frames with a VPL step, no "kept" at 0 (${rows.length} rows; bad: ${chartProblems(rows).join(' ') || 'none'})`);

    // exposure: the daemon encodes the same image again (a new generation, no new VPL step); the
    // page still has its stats and its domain, and says the frame was re-encoded, not "0.0 ms render"
    await page.evaluate(() => {
        window.__renderTexts = [];
        const keep = () => window.__renderTexts.push(`${document.querySelector('#hud-frame').textContent} | ${document.querySelector('#st-render').textContent}`);
        new MutationObserver(keep).observe(document.querySelector('#hud-frame'), { childList: true, characterData: true, subtree: true });
        new MutationObserver(keep).observe(document.querySelector('#st-render'), { childList: true, characterData: true, subtree: true });
    });
    await page.keyboard.press('=');
    await H.waitFor(page, () => window.iir.state.params.exposure === 0.5 && !window.iir.switching &&
        window.iir.lastFrame.generation >= window.iir.generation && window.iir.shownStats);
    r = await readouts(page);
    log(`after exposure +0.5: ${JSON.stringify(r)}`);
    check(r.hud === r.shown.id && r.stats === r.shown.id && r.sites > 0 && /^frame \d+/.test(r.caption),
        `the re-encoded frame ${r.shown.id} has its stats and the domain of its set: "${r.caption}"`);
    // (an exposure change that stops a refinement pass renders anew: the pass left the image half
    // done; with refinement off it re-encodes the frame)
    const reencoded = () => page.evaluate(() => window.__renderTexts.some((t) => /re-encoded, not rendered.*\| re-encoded$/.test(t)));
    const refine = (on) => page.evaluate((on) => { // the Frame & stream form's box (its group folded)
        const box = document.querySelector('#param-refine');
        box.checked = on;
        box.dispatchEvent(new Event('change', { bubbles: true }));
    }, on);
    await refine(false);
    await H.waitFor(page, () => window.iir.state.params.refine === false);
    await H.settle(page, 0, 500);
    await page.mouse.move(10, 10);
    for (let i = 0; i < 3 && !(await reencoded()); i++) {
        await page.keyboard.press(i % 2 ? '=' : '-');
        await H.waitFor(page, () => window.__renderTexts.some((t) => /re-encoded, not rendered.*\| re-encoded$/.test(t)), null, 5000).catch(() => {});
    }
    const texts = await page.evaluate(() => window.__renderTexts);
    check(await reencoded(), `an exposure change gives a re-encoded frame, said so (${texts.length} read-outs)`);
    await refine(true);
    await H.waitFor(page, () => window.iir.state.params.refine === true);
    const zero = texts.filter((t) => /\b0\.0 ms/.test(t));
    log(`render read-outs since: ${texts.slice(0, 4).join(' ;; ')}`);
    check(zero.length === 0, `the image's line and the stats say "re-encoded" for it, never "0.0 ms" (${zero.length} did: ${zero[0] || ''})`);

    // 2./3. aiming: the set changes; crosses are one frame's at most
    const box = await page.locator('#frame').boundingBox();
    await page.mouse.move(box.x + box.width * 0.5, box.y + box.height * 0.85);
    await page.mouse.down();
    let worst = { ratio: 0 };
    let piled = 0;
    let samples = 0;
    for (let i = 1; i <= 24; i++) {
        const a = (i / 24) * 2 * Math.PI;
        await page.mouse.move(box.x + box.width * (0.5 + 0.3 * Math.sin(a)), box.y + box.height * (0.75 + 0.15 * Math.cos(a)), { steps: 2 });
        await H.sleep(120);
        r = await readouts(page);
        const red = r.red;
        samples++;
        if (r.removedDrawn > r.removed) piled++;
        const ratio = red / Math.max(1, r.removedDrawn);
        if (red > RED_PER_CROSS * r.removedDrawn) piled++;
        if (ratio > worst.ratio) worst = { ratio, red, drawn: r.removedDrawn, removed: r.removed, frame: r.domainFrame };
    }
    await page.mouse.up();
    log(`while aiming: worst ${JSON.stringify(worst)}`);
    check(piled === 0, `removed crosses are those of one frame: ${samples} samples, red pixels <= ${RED_PER_CROSS} x crosses drawn <= that frame's removed sites`);
    await H.settle(page, 1);
    await refined(page);
    r = await readouts(page);
    check(r.removedDrawn === 0 && r.red === 0, 'and none once the frame is refined');
    check(r.hud === r.shown.id && r.stats === r.shown.id && r.domain === r.shown.id, `one frame number after the drag: ${r.hud}, ${r.stats}, ${r.domain}`);
    rows = await page.evaluate(() => window.iir.vplChart);
    const kept = rows.filter((x) => x[2] !== null).map((x) => x[2]);
    check(kept.length > 0 && chartProblems(rows).length === 0, `aiming gives incremental steps with VPLs kept (${kept.slice(-5).join(', ')}), still no zero points (bad: ${chartProblems(rows).join(' ') || 'none'})`);
    await page.locator('#domain').scrollIntoViewIfNeeded();
    await page.screenshot({ path: H.shotPath('browser_stats.png') });

    // 4. pt: no VPL domain, said at once and once
    const captions = new Set();
    await page.selectOption('#param-method', 'pt');
    const t0 = Date.now();
    while (Date.now() - t0 < 3000) {
        captions.add(await page.textContent('#domain-caption'));
        const done = await page.evaluate(() => window.iir.state.params.method === 'pt' && window.iir.lastFrame.generation >= window.iir.generation && !window.iir.switching);
        if (done && Date.now() - t0 > 1000) break;
        await H.sleep(20);
    }
    await H.settle(page, 1);
    log(`domain captions during the switch to pt: ${JSON.stringify([...captions])}`);
    check(![...captions].some((c) => /yet/.test(c)), 'never "no domain from pt yet"');
    // pt's frames stream fast: a frame's stats message follows its image, so under load the two can
    // be read between them for a moment; read again (up to 2 s) until they name the same frame
    r = await readouts(page);
    for (const t1 = Date.now(); r.hud !== r.stats && Date.now() - t1 < 2000; r = await readouts(page)) await H.sleep(20);
    check(r.caption === 'pt has no VPL domain', `the caption says "${r.caption}"`);
    check(/^none/.test(r.vpls) && r.hud === r.stats, `the stats say "${r.vpls}"; frame ${r.hud} = ${r.stats}`);

    // ir: VPLs but no disk
    await page.selectOption('#param-method', 'ir');
    await H.waitFor(page, () => window.iir.state.params.method === 'ir' && !window.iir.switching && window.iir.lastDomain && window.iir.shownStats && window.iir.lastFrame.pass === 0);
    r = await readouts(page);
    log(`ir: ${JSON.stringify(r)}`);
    check(/ir has no disk domain/.test(r.caption), `the caption says "${r.caption}"`);
    check(new RegExp(`^${r.imageVpls}\\b`).test(r.vpls) && /new set/.test(r.change), `ir's VPLs: "${r.vpls}", "${r.change}" (${r.imageVpls} on the image)`);
    rows = await page.evaluate(() => window.iir.vplChart);
    const last = rows[rows.length - 1];
    check(last[1] === r.imageVpls && last[2] === null, `its chart row has the set's size and no "kept": ${JSON.stringify(last)}`);

    // 5. rsm: the stats panel lists the counters it declares (recomputed, a share), and the phase
    //    chart its phases (maps, not vpls); iir's panel had none
    check(await page.evaluate(() => document.querySelector('#st-counters').hidden), 'ir declares no counters: none shown');
    await page.selectOption('#param-method', 'rsm');
    await H.waitFor(page, () => window.iir.state.params.method === 'rsm' && !window.iir.switching && window.iir.shownStats && window.iir.shownStats.method === 'rsm');
    await H.waitFor(page, () => /%$/.test(document.querySelector('#st-counter-recomputed')?.textContent || ''));
    const shown = await page.evaluate(() => ({
        label: document.querySelector('#st-counters span')?.textContent,
        value: document.querySelector('#st-counter-recomputed').textContent,
        phases: Object.keys(window.iir.shownStats.phases),
    }));
    log(`rsm: ${JSON.stringify(shown)}`);
    check(shown.label === 'recomputed' && Number(shown.value.slice(0, -1)) > 0, `rsm's counter in the panel: ${shown.label} ${shown.value}`);
    check(shown.phases.join() === 'maps,gbuffer,direct,indirect', `rsm's phases: ${shown.phases.join(', ')}`);

    check(page.problems.length === 0, `no console errors${page.problems.length ? `:\n  ${page.problems.join('\n  ')}` : ''}`);
    await daemon.stop();
}

H.run(main);
