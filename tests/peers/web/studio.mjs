// Foxglove Studio 1.48 in Debian's chromium (puppeteer-core): what it shows of a connection.
//
// usage: node studio.mjs PAGE_URL SCREENSHOT.png TIMEOUT_S [--topic T]... [--text RE] [--image T]
//        [--no-rate] [--frames FILE]
// It opens PAGE_URL (studio.html?ds=foxglove-websocket&ds.url=ws://...), waits until the
// Topics list shows every --topic, types the first one into the Raw Messages panel until its
// text matches --text, waits for the Image panel to draw --image T, saves a screenshot and
// prints one JSON object: {"topics": page text of the topic list, "raw": the matched text,
// "image": true|false}. Every wait is a poll with the deadline TIMEOUT_S. --no-rate: do not wait
// for the first topic's rate. --frames FILE: every WebSocket frame of the page and its workers
// (Studio's Rosbridge source opens its socket in a worker) as JSON lines, {"dir": "sent" or
// "received", "text": a text frame} or {"dir", "binary": its length, "head": its first 128
// bytes in hex}.
import fs from "node:fs";
import puppeteer from "puppeteer-core";

const [page_url, out, timeout_s, ...rest] = process.argv.slice(2);
const topics = [], opts = { text: null, image: false, rate: true, frames: null };
for (let i = 0; i < rest.length; i++) {
  if (rest[i] === "--topic") topics.push(rest[++i]);
  else if (rest[i] === "--text") opts.text = new RegExp(rest[++i]);
  else if (rest[i] === "--image") opts.image = rest[++i];
  else if (rest[i] === "--no-rate") opts.rate = false;
  else if (rest[i] === "--frames") opts.frames = fs.openSync(rest[++i], "w");
}
const deadline = Date.now() + Number(timeout_s) * 1000;
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
async function until(what, probe) {
  while (Date.now() < deadline) {
    const value = await probe();
    if (value) return value;
    await sleep(250);
  }
  throw new Error(`timed out waiting for ${what}`);
}

const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"],
});
// puppeteer starts chromium in a session of its own: the test stops it by this PID (and its
// profile, which no other chromium has) if this driver is killed before it closes the browser
if (process.env.BROWSER_PIDFILE) {
  const profile = browser.process().spawnargs.find((a) => a.startsWith("--user-data-dir=")) ?? "";
  fs.writeFileSync(process.env.BROWSER_PIDFILE, `${browser.process().pid}\n${profile}\n`);
}
const result = { topics: "", raw: "", image: false };
try {
  const page = await browser.newPage();
  if (opts.frames !== null) {
    // CDP's Network events, of the page's session and of each worker's
    const log = (dir) => ({ response }) => {
      const frame = response.opcode === 1 ? { dir, text: response.payloadData }
        : { dir, binary: Buffer.from(response.payloadData, "base64").length,
          head: Buffer.from(response.payloadData, "base64").subarray(0, 128).toString("hex") };
      fs.writeSync(opts.frames, JSON.stringify(frame) + "\n");
    };
    const watch = (client) => {
      client.on("Network.webSocketFrameSent", log("sent"));
      client.on("Network.webSocketFrameReceived", log("received"));
    };
    watch(await page.createCDPSession().then(async (c) => (await c.send("Network.enable"), c)));
    page.on("workercreated", (worker) => watch(worker.client));
  }
  await page.setViewport({ width: 1400, height: 900 });
  // puppeteer's own waits (30 s by default) get the whole deadline: under load, chromium took
  // longer than 30 s to parse Studio's 56 MB bundle
  page.setDefaultTimeout(Number(timeout_s) * 1000);
  await page.goto(page_url, { waitUntil: "domcontentloaded" });
  const text = () => page.evaluate(() => document.body.innerText);
  // the left sidebar's Topics tab lists the connection's topics with types and rates
  await until("the Topics tab", async () => {
    const tab = await page.$('[data-testid="topics-left"], button[title="Topics"], [aria-label="Topics"]');
    if (tab) await tab.click().catch(() => {});
    const body = await text();
    return topics.every((t) => body.includes(t));
  });
  result.topics = await text();
  if (topics.length && opts.text) {
    const input = await until("the Raw Messages path box", () =>
      page.$('input[placeholder="/some/topic.msgs[0].field"]'));
    await input.click();
    await page.keyboard.type(topics[0]);
    await page.keyboard.press("Escape");
    result.raw = await until(`the raw message to match ${opts.text}`, async () => {
      const m = (await text()).match(opts.text);
      return m && m[0];
    });
  }
  if (topics.length && opts.rate) {
    // the Topics panel gives a subscribed topic its count and rate: "/t", its type, N, "9.9 Hz"
    const escaped = topics[0].replace(/[.*+?^${}()|[\]\\]/g, "\\$&");
    const rated = new RegExp(escaped + "\\n[^\\n]+\\n\\d+\\n[\\d.]+ Hz");
    await until(`a rate for ${topics[0]}`, async () => rated.test(await text()));
    result.topics = await text();
  }
  if (opts.image) {
    // the default layout's Image panel takes the first image topic; it says it waits until one
    // draws (on WebGL, so the pixels are the screenshot's to check)
    result.image = await until("the Image panel to draw", async () => {
      const body = await text();
      return body.includes(opts.image) && !body.includes("Waiting for images");
    });
    await until("the topic rates", async () => /\d+(\.\d+)? Hz/.test(await text()));
    result.topics = await text();
  }
} catch (err) {
  result.error = String(err.message || err);
} finally {
  const [page] = (await browser.pages()).slice(-1);
  if (page) await page.screenshot({ path: out }).catch(() => {});
  await browser.close();
  process.stdout.write(JSON.stringify(result) + "\n");
}
