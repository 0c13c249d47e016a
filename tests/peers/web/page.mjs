// A web page in Debian's chromium (puppeteer-core), driven by commands, read by events.
//
// usage: node page.mjs PAGE_URL SCREENSHOT.png
// Opens PAGE_URL, then reads one JSON command a line on stdin and prints one JSON event a line:
//   {"do": "text", "selector": S, "match": RE, "timeout": SECONDS}
//       -> {"event": "text", "text": S's innerText once it matches RE}
//   {"do": "click", "selector": S}  -> {"event": "clicked"}
//   {"do": "close"} (or stdin's end) -> a screenshot, then {"event": "closed"}
// and, as they happen: {"event": "console", "type", "text"}, {"event": "pageerror", "text"},
// {"event": "refused", "url"} for a request off loopback (refused: tests stay on loopback),
// {"event": "http", "status", "url"} for an answer of 400 or more,
// {"event": "ws", "dir": "sent"|"received", "data"} for each WebSocket frame (its first 500
// characters),
// {"event": "error", "text"} for a command that failed (a wait says the text it saw; it ends at
// the page's first uncaught error).
import fs from "node:fs";
import readline from "node:readline";
import puppeteer from "puppeteer-core";

const [page_url, out] = process.argv.slice(2);
const say = (event) => process.stdout.write(JSON.stringify(event) + "\n");
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox"],
});
// puppeteer starts chromium in a session of its own: the test stops it by this PID (and its
// profile, which no other chromium has) if this driver is killed before it closes the browser
if (process.env.BROWSER_PIDFILE) {
  const profile = browser.process().spawnargs.find((a) => a.startsWith("--user-data-dir=")) ?? "";
  fs.writeFileSync(process.env.BROWSER_PIDFILE, `${browser.process().pid}\n${profile}\n`);
}
const page = await browser.newPage();
await page.setViewport({ width: 800, height: 400 });
page.on("console", (m) => say({ event: "console", type: m.type(), text: m.text() }));
let broken = null; // the page's first uncaught error: a wait on it ends there
page.on("pageerror", (e) => {
  broken ??= String(e.message || e);
  say({ event: "pageerror", text: String(e.message || e) });
});
// the page's WebSocket frames, as chromium saw them (a failing test's evidence)
const cdp = await page.createCDPSession();
await cdp.send("Network.enable");
const frame = (dir) => (e) => say({ event: "ws", dir, data: e.response.payloadData.slice(0, 500) });
cdp.on("Network.webSocketFrameSent", frame("sent"));
cdp.on("Network.webSocketFrameReceived", frame("received"));
await page.setRequestInterception(true);
page.on("request", (request) => {
  const host = new URL(request.url()).hostname;
  if (host === "127.0.0.1" || host === "localhost") return request.continue();
  say({ event: "refused", url: request.url() });
  return request.abort();
});
page.on("response", (r) => r.status() >= 400 && say({ event: "http", status: r.status(), url: r.url() }));
await page.goto(page_url, { waitUntil: "domcontentloaded" });
say({ event: "open" });

async function text({ selector, match, timeout }) {
  const pattern = new RegExp(match, "m");
  const deadline = Date.now() + Number(timeout) * 1000;
  let seen = "";
  while (Date.now() < deadline && !broken) {
    seen = await page.$eval(selector, (e) => e.innerText).catch(() => "");
    if (pattern.test(seen)) return { event: "text", text: seen };
    await sleep(100);
  }
  const why = broken ? `the page failed (${broken})` : "out of time";
  throw new Error(`${selector} never matched ${match} (${why}); it showed ${JSON.stringify(seen)}`);
}

async function close() {
  await page.screenshot({ path: out }).catch(() => {});
  await browser.close();
  say({ event: "closed" });
  process.exit(0);
}

const lines = readline.createInterface({ input: process.stdin });
for await (const line of lines) {
  const command = JSON.parse(line);
  try {
    if (command.do === "text") say(await text(command));
    else if (command.do === "click") {
      await page.click(command.selector);
      say({ event: "clicked" });
    } else if (command.do === "close") await close();
    else say({ event: "error", text: `no such command: ${command.do}` });
  } catch (err) {
    say({ event: "error", text: String(err.message || err) });
  }
}
await close();
