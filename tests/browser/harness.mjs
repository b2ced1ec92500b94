// harness.mjs -- what the browser tests (test_*.mjs here) and tools/issue16_shots.mjs share: the
// prerequisites (fail, never skip), a real `iird serve` on a free port, headless Chromium through
// playwright-core with the page's console errors collected, a scenes folder with the scenes the
// tests need beyond the shipped ones, and pixel reads of canvases and of screenshots (what is on
// screen, CSS filters and overlays included). Not a test itself (ctest runs only test_*.mjs).

import { spawn, execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

export const CHROMIUM = '/usr/bin/chromium';
// Frames under ASan take ~0.2-0.7 s on this 2-core machine; waits are generous, the tests are not.
export const WAIT_MS = Number(process.env.IIR_TEST_FRAME_TIMEOUT || 20) * 1000;
export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// ---- reporting ----

const T0 = Date.now();
let failures = 0;
let cleanups = [];

export function log(msg) {
    console.log(`[${((Date.now() - T0) / 1000).toFixed(1)} s] ${msg}`);
}

export function fail(msg) {
    console.error(`FAIL: ${msg}`);
    failures++;
}

export function check(cond, msg) {
    if (cond) log(`ok: ${msg}`);
    else fail(msg);
    return !!cond;
}

export function onCleanup(fn) {
    cleanups.push(fn);
}

async function cleanup() {
    const fns = cleanups.reverse();
    cleanups = [];
    for (const fn of fns) await Promise.resolve().then(fn).catch(() => {});
}

// Runs main() and exits 0 when nothing failed; "N passed, M failed" as ctest's other tests print.
export function run(main) {
    main().then(
        async () => {
            await cleanup();
            console.log(failures ? '0 passed, 1 failed' : '1 passed, 0 failed');
            process.exit(failures ? 1 : 0);
        },
        async (e) => {
            console.error(`FAIL: ${e.stack || e}`);
            await cleanup();
            console.log('0 passed, 1 failed');
            process.exit(1);
        },
    );
}

// ---- prerequisites: fail, never skip ----

export async function prerequisites(IIRD, SRC) {
    const need = (ok, msg) => {
        if (!ok) throw new Error(msg);
    };
    need(IIRD && SRC, 'usage: node test_X.mjs IIRD SOURCE_DIR');
    need(fs.existsSync(IIRD), `${IIRD} does not exist: build it first (cmake --build BUILD --target iird)`);
    need(fs.existsSync(CHROMIUM), `${CHROMIUM} is missing: run \`make deps\` (installs Debian's chromium)`);
    const pw = path.join(SRC, 'node_modules', 'playwright-core', 'index.mjs');
    need(fs.existsSync(pw), `${pw} is missing: run \`make web-deps\` (npm ci from package-lock.json)`);
    const uplot = path.join(SRC, 'web', 'vendor', 'uplot', 'uPlot.esm.js');
    need(fs.existsSync(uplot), `${uplot} is missing: run \`make web-deps\` (copies uPlot into web/vendor/)`);
    return (await import(pathToFileURL(pw).href)).chromium;
}

// ---- the daemon ----

// `--web DIR` when the daemon has that option (else it finds web/ in its source tree).
export function webArgs(IIRD, webDir) {
    let help = '';
    try {
        help = execFileSync(IIRD, ['serve', '--help'], { encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
    } catch (e) {
        help = `${e.stdout || ''}${e.stderr || ''}`;
    }
    return help.includes('--web') ? ['--web', webDir] : [];
}

export class Daemon {
    // args: everything after `serve` (port, scenes, web...). Unless they say otherwise the daemon
    // does not drain its sessions on SIGTERM (--drain-seconds 0): the page is still connected when
    // a test stops it, and the default drain would wait its 10 s for the page to leave
    // (tests/integration/test_serve_drain.py tests the drain).
    constructor(IIRD, args) {
        if (!args.includes('--drain-seconds')) args = [...args, '--drain-seconds', '0'];
        // small frames unless a test asks for its own: the sanitizer build renders 512x384 four
        // times slower, and what the tests check (the page, the protocol, what changes) does not
        // depend on the size
        if (!args.includes('--size')) args = [...args, '--size', '256x192'];
        fs.mkdirSync(process.env.IIR_TEST_TMP || os.tmpdir(), { recursive: true });
        this.dir = fs.mkdtempSync(path.join(process.env.IIR_TEST_TMP || os.tmpdir(), 'iird-browser-'));
        this.out = path.join(this.dir, 'stdout');
        this.err = path.join(this.dir, 'stderr');
        this.cmd = `${IIRD} serve ${args.join(' ')}`;
        const env = { ASAN_OPTIONS: 'detect_leaks=1', UBSAN_OPTIONS: 'print_stacktrace=1', OMP_NUM_THREADS: '2', ...process.env };
        this.proc = spawn(IIRD, ['serve', ...args], {
            env,
            stdio: ['ignore', fs.openSync(this.out, 'w'), fs.openSync(this.err, 'w')],
        });
        this.exit = new Promise((resolve) => this.proc.on('exit', (code, signal) => resolve({ code, signal })));
        this.exited = null;
        this.exit.then((x) => (this.exited = x));
        onCleanup(async () => {
            if (!this.exited) {
                this.proc.kill('SIGKILL');
                await this.exit;
            }
        });
    }

    // The URL from "iird: serving http://127.0.0.1:PORT/".
    async url(timeoutMs = 30000) {
        const deadline = Date.now() + timeoutMs;
        while (Date.now() < deadline) {
            const m = /iird: serving (http:\/\/127\.0\.0\.1:(\d+)\/)/.exec(fs.readFileSync(this.out, 'utf8'));
            if (m) return { url: m[1], port: Number(m[2]) };
            if (this.exited) throw new Error(`${this.cmd} exited ${JSON.stringify(this.exited)} before serving:\n${this.stderr()}`);
            await sleep(50);
        }
        throw new Error(`${this.cmd} printed no "iird: serving" line in ${timeoutMs} ms:\n${this.stderr()}`);
    }

    stderr() {
        return fs.existsSync(this.err) ? fs.readFileSync(this.err, 'utf8') : '';
    }

    // SIGTERM, then the exit status must be 0 and stderr free of sanitizer reports; the daemon's
    // output files are removed when it passed.
    async stop() {
        if (!this.exited) this.proc.kill('SIGTERM');
        const res = await Promise.race([this.exit, sleep(20000).then(() => null)]);
        if (!res) {
            this.proc.kill('SIGKILL');
            await this.exit;
            fail(`${this.cmd} did not stop within 20 s of SIGTERM`);
            return;
        }
        const err = this.stderr();
        const san = /(ERROR: AddressSanitizer|LeakSanitizer|runtime error:)/.exec(err);
        if (san) fail(`sanitizer report from the daemon:\n${err.slice(Math.max(0, san.index - 200), san.index + 3000)}`);
        if (res.code !== 0) fail(`${this.cmd} exited ${JSON.stringify(res)} after SIGTERM:\n${err.slice(-2000)}`);
        if (!san && res.code === 0) fs.rmSync(this.dir, { recursive: true, force: true }); // kept on failure
    }
}

// A daemon on a free port, or on `port` (a daemon just stopped may need a moment to free it):
// {daemon, url, port}.
export async function startDaemon(IIRD, args, port = 0) {
    for (let attempt = 0; ; attempt++) {
        const d = new Daemon(IIRD, ['--port', String(port), ...args]);
        try {
            return { daemon: d, ...(await d.url()) };
        } catch (e) {
            if (attempt >= 10 || port === 0) throw e;
            await d.exit;
            await sleep(300);
        }
    }
}

// disc_lamp's light: a 0.8 x 0.8 area light at the back wall's middle facing +z (r = +x, u = +y),
// emitting from the 32-gon inscribed in it (corners at radius 1/2 of its light-local square).
const DISC_SIDES = 32;
export const DISC_LAMP = {
    type: 'area', name: 'disc', position: [0, 1, -0.95], direction: [0, 0, 1], up: [0, 1, 0], size: [0.8, 0.8], intensity: 4,
    shape: Array.from({ length: DISC_SIDES }, (_, k) => {
        const at = (i) => [0.5 * Math.cos((2 * Math.PI * i) / DISC_SIDES), 0.5 * Math.sin((2 * Math.PI * i) / DISC_SIDES)];
        return [[0, 0], at(k), at(k + 1)];
    }),
};

// A scenes folder for the tests: the shipped Cornell box, and scenes on its geometry that the
// shipped ones do not cover: point_box (one point light), dark_box (no light at all: iird makes up a
// spot), two_lights (a spot and a point light 'bulb'), glow_box (a spot, with the box's ceiling
// lamp left emitting: a material whose indirect light iir leaves out) and disc_lamp (an area light
// 'disc' on the back wall facing the camera, shaped as a 32-gon: DISC_LAMP); with {conference: true} the
// shipped conference room too (a scene that takes a while to load). Removed at exit.
export function makeScenes(SRC, { conference = false } = {}) {
    fs.mkdirSync(process.env.IIR_TEST_TMP || os.tmpdir(), { recursive: true });
    const dir = fs.mkdtempSync(path.join(process.env.IIR_TEST_TMP || os.tmpdir(), 'iird-scenes-'));
    onCleanup(() => fs.rmSync(dir, { recursive: true, force: true }));
    const box = path.join(SRC, 'scenes', 'cornell_box');
    fs.cpSync(box, path.join(dir, 'cornell_box'), { recursive: true });
    if (conference) fs.cpSync(path.join(SRC, 'scenes', 'conference'), path.join(dir, 'conference'), { recursive: true });
    const camera = { position: [0, 1, 3.9], target: [0, 1, 0], up: [0, 1, 0], fov_y: 39.3 };
    const scenes = {
        point_box: [{ type: 'point', name: 'bulb', position: [0, 1.5, 0], intensity: 1.5 }],
        dark_box: [],
        two_lights: [
            { type: 'spot', name: 'spot', position: [0, 1.9, 0], direction: [0, -1, 0], cone_angle: 60, intensity: [4, 3, 1] },
            { type: 'point', name: 'bulb', position: [0.5, 1.5, 0], intensity: 1.5 },
        ],
        glow_box: [
            { type: 'spot', name: 'spot', position: [0, 1.9, 0], direction: [0, -1, 0], cone_angle: 60, intensity: [4, 3, 1] },
        ],
        disc_lamp: [DISC_LAMP],
    };
    for (const [name, lights] of Object.entries(scenes)) {
        const d = path.join(dir, name);
        fs.mkdirSync(d);
        for (const f of ['CornellBox-Original.obj', 'CornellBox-Original.mtl']) fs.copyFileSync(path.join(box, f), path.join(d, f));
        const sidecar = { file: 'CornellBox-Original.obj', camera, lights };
        if (name !== 'glow_box') sidecar.materials = { light: { emission: 0 } };
        fs.writeFileSync(path.join(d, `${name}.scene.json`), JSON.stringify(sidecar, null, 2));
    }
    return dir;
}

// ---- the browser ----

export async function launch(chromium) {
    const browser = await chromium.launch({
        executablePath: CHROMIUM,
        headless: true,
        args: ['--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage', '--disable-background-networking'],
    });
    onCleanup(() => browser.close());
    return browser;
}

// A page whose console errors, uncaught exceptions, failed requests and "iir:" warnings (the
// page's log of server errors) are collected in page.problems, except warnings matching
// `expected` (a regex: errors the test provokes on purpose).
export async function newPage(browser, { expected = null, width = 1280, height = 800 } = {}) {
    const page = await browser.newPage({ viewport: { width, height } });
    page.problems = [];
    page.on('console', (m) => {
        const text = m.text();
        if (m.type() === 'warning' && text.startsWith('iir:') && !(expected && expected.test(text))) page.problems.push(text);
        // Chromium logs every refused WebSocket connect: expected only while the test has the
        // daemon down (page.daemonDown).
        if (page.daemonDown && /WebSocket connection to .* failed|ERR_CONNECTION_REFUSED/.test(text)) return;
        if (m.type() === 'error') page.problems.push(text);
    });
    page.on('pageerror', (e) => page.problems.push(`uncaught: ${e.message}`));
    await recordWire(page); // every page: a failure message ends with the wire's last messages
    page.on('requestfailed', (r) => {
        if (!page.daemonDown) page.problems.push(`request failed: ${r.url()} ${r.failure() && r.failure().errorText}`);
    });
    return page;
}

// Loads the client and waits for its first frame.
export async function open(page, url) {
    await page.goto(url, { waitUntil: 'load' });
    await page.waitForFunction(() => window.iir && window.iir.framesDrawn > 0, null, { timeout: WAIT_MS });
}

// The daemon flag for a still of `passes` refinement passes; a test that does not study refinement
// takes 8. The product's 64 are, under ASan, most of such a test's CPU (the session refines after
// every input while the test goes on: test_arrow_tilt's daemon 45 CPU seconds with 64, 12 with 8).
export const refineArgs = (passes = 8) => ['--refine-passes', String(passes)];

// A daemon on the built-in Cornell box with small frames (256x192, 64^2 shadow maps) and a page on
// it, settled: where a test that drives one session through the page starts. A still has
// `refinePasses` passes (refineArgs' default unless the test needs more).
export async function openSmallSession(IIRD, SRC, { refinePasses } = {}) {
    const chromium = await prerequisites(IIRD, SRC);
    const { daemon, url } = await startDaemon(IIRD, ['--size', '256x192', '--sm-res', '64', ...refineArgs(refinePasses),
        ...webArgs(IIRD, path.join(SRC, 'web'))]);
    log(`daemon at ${url} (${daemon.cmd})`);
    const browser = await launch(chromium);
    const page = await newPage(browser);
    await open(page, url);
    await settle(page, 1);
    return { daemon, page };
}

// A shift-drag of the spot (the light in the view plane) from 30% down the middle of the frame:
// `moves` moves `delayMs` apart, x swinging by +-amp of the frame's width, `turns` times.
export async function shiftDrag(page, { moves, amp, turns, delayMs }) {
    const box = await page.locator('#frame').boundingBox();
    const cx = box.x + box.width * 0.5;
    const cy = box.y + box.height * 0.3;
    await page.keyboard.down('Shift');
    await page.mouse.move(cx, cy);
    await page.mouse.down();
    for (let i = 1; i <= moves; i++) {
        await page.mouse.move(cx + box.width * amp * Math.sin((2 * Math.PI * turns * i) / moves), cy);
        await sleep(delayMs);
    }
    await page.mouse.up();
    await page.keyboard.up('Shift');
}

// Sets method parameter `name` through its panel field and waits for the state to carry it.
export async function setParam(page, name, value) {
    const input = page.locator(`#param-${name}`);
    await input.fill(String(value));
    await input.press('Enter');
    await input.blur();
    await waitFor(page, ([n, v]) => window.iir.state.params[n] === v, [name, value]);
}

// Waits until every input the page has (a key's move goes out on the next animation frame) is sent
// and answered by a drawn frame, and then for `more` frames or until no frame came for `quietMs`
// (the session has converged and idles).
export async function settle(page, more = 2, quietMs = 2000) {
    await page.waitForFunction(() => {
        const f = window.iir.lastFrame;
        return f && !window.iir.switching && !window.iir.inputPending && (window.iir.inputSeq > 0 ? f.seq !== 0xffffffff && f.seq >= window.iir.inputSeq : true);
    }, null, { timeout: WAIT_MS }).catch(async (e) => {
        throw new Error(`${e.message}\npage: ${JSON.stringify(await pageState(page))}`);
    });
    const n = await page.evaluate(() => window.iir.framesDrawn);
    await page.waitForFunction(({ n, quietMs }) => window.iir.framesDrawn >= n ||
        performance.now() - window.iir.lastFrame.drawnAt > quietMs, { n: n + more, quietMs }, { timeout: WAIT_MS }).catch(() => {});
}

// What the page shows, for failure messages.
export function pageState(page) {
    return page.evaluate(() => {
        const i = window.iir;
        const f = i.lastFrame;
        return {
            scene: i.state && i.state.scene, method: i.state && i.state.params.method, generation: i.generation,
            switching: i.switching, greyed: i.greyed, curtain: i.curtain, errors: i.errors, inputSeq: i.inputSeq, inputPending: i.inputPending,
            lastFrame: f && { id: f.frameId, seq: f.seq, generation: f.generation, pass: f.pass }, held: i.framesHeld,
            wire: (window.__wire || []).slice(-24).map((m) => `${(m.t / 1000).toFixed(2)} s ${m.dir} ${m.type} seq=${m.seq} gen=${m.generation} frame=${m.frame}${m.code ? ` code=${m.code}` : ""}`),
        };
    });
}

// page.waitForFunction that says what the page showed when it times out.
export async function waitFor(page, fn, arg = null, timeout = WAIT_MS) {
    try {
        await page.waitForFunction(fn, arg, { timeout });
    } catch (e) {
        throw new Error(`${e.message.split('\n')[0]} waiting for ${fn.toString().slice(0, 200)}\npage: ${JSON.stringify(await pageState(page), null, 1)}`);
    }
}

// ---- pixels ----

// Where a test writes screenshot `name`: the build's test-tmp dir (IIR_TEST_TMP, as ctest sets it),
// else the system's temporary dir (never the working dir: run from the source tree they were
// committed by mistake).
export function shotPath(name) {
    const dir = process.env.IIR_TEST_TMP || path.join(os.tmpdir(), 'iir-browser');
    fs.mkdirSync(dir, { recursive: true });
    return path.join(dir, name);
}

// Mean absolute difference (0-255) of two RGB arrays.
export function mad(a, b) {
    let s = 0;
    for (let i = 0; i < a.length; i++) s += Math.abs(a[i] - b[i]);
    return s / a.length;
}

// RGB of a canvas, downsampled to w x h in the page (the read-back of a same-origin canvas).
export async function canvasRGB(page, id, w, h) {
    return page.evaluate(({ id, w, h }) => {
        const src = document.getElementById(id);
        const c = document.createElement('canvas');
        c.width = w;
        c.height = h;
        const ctx = c.getContext('2d', { willReadFrequently: true });
        ctx.imageSmoothingQuality = 'high';
        ctx.drawImage(src, 0, 0, w, h);
        const d = ctx.getImageData(0, 0, w, h).data;
        const out = new Array(w * h * 3);
        for (let i = 0, j = 0; i < d.length; i += 4) {
            out[j++] = d[i];
            out[j++] = d[i + 1];
            out[j++] = d[i + 2];
        }
        return out;
    }, { id, w, h });
}

// What is on screen in the element's box (a screenshot, so CSS filters and overlays count), as RGB
// downsampled to w x h, decoded in the page. Also saves the screenshot when `save` is a path.
export async function screenRGB(page, selector, w, h, save = null) {
    const box = await page.locator(selector).boundingBox();
    const png = await page.screenshot({ clip: box });
    if (save) fs.writeFileSync(save, png);
    return page.evaluate(async ({ b64, w, h }) => {
        const img = new Image();
        img.src = `data:image/png;base64,${b64}`;
        await img.decode();
        const c = document.createElement('canvas');
        c.width = w;
        c.height = h;
        const ctx = c.getContext('2d', { willReadFrequently: true });
        ctx.drawImage(img, 0, 0, w, h);
        const d = ctx.getImageData(0, 0, w, h).data;
        const out = new Array(w * h * 3);
        for (let i = 0, j = 0; i < d.length; i += 4) {
            out[j++] = d[i];
            out[j++] = d[i + 1];
            out[j++] = d[i + 2];
        }
        return out;
    }, { b64: png.toString('base64'), w, h });
}

// Pixels of the overlay canvas (#overlay: VPLs, the light's gizmo) within `radius` frame pixels of
// frame pixel (x, y) whose colour is within `tol` of rgb: how much of the gizmo is drawn there.
export async function overlayPixelsNear(page, x, y, radius, rgb, tol = 40) {
    return page.evaluate(({ x, y, radius, rgb, tol }) => {
        const o = document.getElementById('overlay');
        const f = document.getElementById('frame');
        const sx = o.width / f.width;
        const sy = o.height / f.height;
        const cx = x * sx;
        const cy = y * sy;
        const r = radius * sx;
        const x0 = Math.max(0, Math.floor(cx - r));
        const y0 = Math.max(0, Math.floor(cy - r));
        const w = Math.min(o.width, Math.ceil(cx + r)) - x0;
        const h = Math.min(o.height, Math.ceil(cy + r)) - y0;
        if (w <= 0 || h <= 0) return 0;
        const d = o.getContext('2d').getImageData(x0, y0, w, h).data;
        let n = 0;
        for (let j = 0; j < h; j++) {
            for (let i = 0; i < w; i++) {
                const k = 4 * (j * w + i);
                if (d[k + 3] < 200) continue;
                if ((x0 + i - cx) ** 2 + (y0 + j - cy) ** 2 > r * r) continue;
                if (Math.abs(d[k] - rgb[0]) <= tol && Math.abs(d[k + 1] - rgb[1]) <= tol && Math.abs(d[k + 2] - rgb[2]) <= tol) n++;
            }
        }
        return n;
    }, { x, y, radius, rgb, tol });
}

// The pinhole projection of core/src/camera.c, written again here so the tests check the page's
// gizmo against it: world point p to frame pixels {x, y}, or null behind the camera.
export function project(cam, width, height, p) {
    const sub = (a, b) => a.map((x, i) => x - b[i]);
    const dot = (a, b) => a.reduce((s, x, i) => s + x * b[i], 0);
    const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    const norm = (a) => a.map((x) => x / Math.sqrt(dot(a, a)));
    const f = norm(sub(cam.target, cam.position));
    const r = norm(cross(f, cam.up));
    const u = cross(r, f);
    const d = sub(p, cam.position);
    const z = dot(d, f);
    if (z <= 0) return null;
    const t = Math.tan((cam.fov * Math.PI) / 360);
    return { x: (1 + dot(d, r) / (z * t * (width / height))) * width / 2, y: (1 - dot(d, u) / (z * t)) * height / 2 };
}

// Mean brightness (0-255) and mean saturation (max - min channel, 0-255) of RGB pixels.
export function tone(rgb) {
    let lum = 0;
    let sat = 0;
    const n = rgb.length / 3;
    for (let i = 0; i < rgb.length; i += 3) {
        const [r, g, b] = [rgb[i], rgb[i + 1], rgb[i + 2]];
        lum += (r + g + b) / 3;
        sat += Math.max(r, g, b) - Math.min(r, g, b);
    }
    return { lum: lum / n, sat: sat / n };
}

// ---- the wire, as the page sees it ----

// Records, in the page, every message on the client's WebSocket with performance.now(): window.__wire
// holds {t, socket (1, 2, ... per WebSocket the page opened), dir: 'out'|'in', type, seq, generation,
// frame, position (a state's light), name (a message's: the light a `light` message moves)}. Call
// before loading the page (newPage does, for every page; again is harmless).
export async function recordWire(page) {
    if (page.wireRecorded) return;
    page.wireRecorded = true;
    await page.addInitScript(() => {
        const log = (window.__wire = []);
        const Native = window.WebSocket;
        let sockets = 0;
        window.WebSocket = class extends Native {
            constructor(...args) {
                super(...args);
                const socket = ++sockets;
                this.socket = socket;
                this.addEventListener('message', (ev) => {
                    const t = performance.now();
                    if (typeof ev.data === 'string') {
                        const m = JSON.parse(ev.data);
                        const generation = m.generation ?? (m.state && m.state.generation);
                        const light = m.light || (m.state && m.state.light);
                        log.push({ t, socket, dir: 'in', type: m.type, seq: m.seq, generation, code: m.code, frame: m.frame, position: light && light.position });
                    } else if (ev.data instanceof ArrayBuffer) {
                        const dv = new DataView(ev.data);
                        const kind = dv.getUint8(4);
                        log.push({ t, socket, dir: 'in', type: kind === 1 ? 'frame' : 'file', frame: dv.getUint32(8, true), generation: dv.getUint32(40, true) });
                    }
                });
            }

            send(data) {
                const m = JSON.parse(data);
                log.push({ t: performance.now(), socket: this.socket, dir: 'out', type: m.type, seq: m.seq, name: m.name });
                return super.send(data);
            }
        };
    });
}

// Checks the frames the page drew against the wire: none whose generation is below that of the
// newest state (or welcome) received before it was drawn, none drawn between sending a scene or
// params message and its reply, and each drawn frame's generation is the one its header carried.
// Returns {drawn, switches, problems: [text]}.
export async function frameDiscipline(page) {
    const { wire, drawn } = await page.evaluate(() => ({ wire: window.__wire, drawn: window.iir.drawn }));
    const problems = [];
    // A new socket is a new session: its generations and frame ids start again.
    const first = new Map();
    for (const m of wire) if (m.dir === 'in' && !first.has(m.socket)) first.set(m.socket, m.t);
    const starts = [...first.values()];
    const since = (t) => Math.max(-Infinity, ...starts.filter((s) => s <= t));
    const states = wire.filter((m) => m.dir === 'in' && (m.type === 'state' || m.type === 'welcome'));
    const frameOf = (d) => wire.find((m) => m.type === 'frame' && m.frame === d.frameId && m.t <= d.t && m.t >= since(d.t));
    for (const d of drawn) {
        const before = states.filter((m) => m.t < d.t && m.t >= since(d.t));
        const g = before.length ? Math.max(...before.map((m) => m.generation)) : 0;
        if (d.generation < g) problems.push(`frame ${d.frameId} of generation ${d.generation} drawn after a state of generation ${g}`);
        const w = frameOf(d);
        if (w && w.generation !== d.generation) problems.push(`frame ${d.frameId}: drawn as generation ${d.generation}, header says ${w.generation}`);
    }
    const switches = [];
    for (const out of wire.filter((m) => m.dir === 'out' && (m.type === 'scene' || m.type === 'params'))) {
        const reply = wire.find((m) => m.dir === 'in' && m.socket === out.socket && m.seq === out.seq && (m.type === 'state' || m.type === 'error'));
        const end = reply ? reply.t : Infinity;
        const during = drawn.filter((d) => d.t > out.t && d.t < end);
        switches.push({ type: out.type, seq: out.seq, reply: reply ? reply.type : null, ms: end - out.t, drawnDuring: during.length });
        if (during.length) problems.push(`${during.length} frame(s) drawn between ${out.type} seq ${out.seq} and its ${reply ? reply.type : 'missing reply'}`);
    }
    return { drawn: drawn.length, switches, problems };
}
