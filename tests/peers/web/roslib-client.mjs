// roslib 2.1.0 (on `ws`) against a rosbridge v2 server with tests/support/ros1_nodes/rosbridge_graph.py
// on its graph: the checks a roslib page makes. One JSON line per check, then a summary line;
// exits 1 if any check failed. Lives here, beside node_modules: roslib 2.x is ESM only.
//
// usage: node roslib-client.mjs URL [SCALE]   (SCALE multiplies every deadline: the run's load factor)
import { Ros, Topic, Service, Param } from "roslib";

const url = process.argv[2];
const scale = Number(process.argv[3] || 1);
const results = [];
const log = (ok, name, detail) => {
  results.push({ ok, name });
  console.log(JSON.stringify({ check: name, ok, detail }));
};
// Every wait is bounded: `ms` on a quiet machine, times the load factor.
const within = (ms, what, fn) => new Promise((resolve, reject) => {
  const t = setTimeout(() => reject(new Error(`timeout after ${ms * scale} ms: ${what}`)), ms * scale);
  fn((v) => { clearTimeout(t); resolve(v); }, (e) => { clearTimeout(t); reject(new Error(String(e))); });
});
async function check(name, fn) {
  try {
    const [ok, detail] = await fn();
    log(ok, name, detail);
  } catch (e) {
    log(false, name, e.message);
  }
}

const ros = new Ros({});
ros.on("error", (e) => console.error("ros error", e?.message ?? e));
await check("connect", async () => {
  await within(10000, "connect", (res, rej) => { ros.on("connection", res); ros.connect(url).catch(rej); });
  return [true, url];
});

await check("getTopics", async () => {
  const r = await within(10000, "getTopics", (res, rej) => ros.getTopics(res, rej));
  const i = r.topics.indexOf("/chatter");
  return [i >= 0 && r.types[i] === "std_msgs/String", { topics: r.topics, types: r.types }];
});
await check("getServices", async () => {
  const r = await within(10000, "getServices", (res, rej) => ros.getServices(res, rej));
  return [r.includes("/set_flag") && r.includes("/rosapi/topics"), r];
});
await check("getNodes", async () => {
  const r = await within(10000, "getNodes", (res, rej) => ros.getNodes(res, rej));
  return [r.includes("/rbs_ros_side"), r];
});
await check("getTopicType", async () => {
  const r = await within(10000, "getTopicType", (res, rej) => ros.getTopicType("/chatter", res, rej));
  return [r === "std_msgs/String", r];
});
await check("getServiceType", async () => {
  const r = await within(10000, "getServiceType", (res, rej) => ros.getServiceType("/set_flag", res, rej));
  return [r === "std_srvs/SetBool", r];
});
await check("getMessageDetails", async () => {
  const r = await within(10000, "getMessageDetails",
    (res, rej) => ros.getMessageDetails("geometry_msgs/PoseStamped", res, rej));
  const types = r.map((t) => t.type);
  return [types[0] === "geometry_msgs/PoseStamped" && types.includes("geometry_msgs/Quaternion"), types];
});
await check("Param get and set", async () => {
  const g = new Param({ ros, name: "/rbs_test/greeting" });
  const v = await within(10000, "get", (res, rej) => g.get(res, rej));
  const p = new Param({ ros, name: "/rbs_test/from_roslib" });
  await within(10000, "set", (res, rej) => p.set({ a: 1, b: [1.5, "x"] }, res, rej));
  const w = await within(10000, "get", (res, rej) => p.get(res, rej));
  return [v === "hello from rosparam" && w?.a === 1 && w?.b?.[1] === "x", { greeting: v, from_roslib: w }];
});

await check("subscribe (JSON), 10 messages", async () => {
  const t = new Topic({ ros, name: "/chatter", messageType: "std_msgs/String" });
  const got = [];
  await within(20000, "chatter", (res) => t.subscribe((m) => { got.push(m.data); if (got.length === 10) res(); }));
  t.unsubscribe();
  return [got.every((d) => /^hello \d+$/.test(d)), { first: got[0], last: got[9] }];
});
await check("subscribe (compression cbor)", async () => {
  const t = new Topic({ ros, name: "/chatter", messageType: "std_msgs/String", compression: "cbor" });
  const m = await within(10000, "cbor chatter", (res) => t.subscribe(res));
  t.unsubscribe();
  return [/^hello \d+$/.test(m.data), m];
});

const echo = new Topic({ ros, name: "/from_web_echo", messageType: "std_msgs/String" });
const echoes = [];
const waiters = [];
echo.subscribe((m) => { echoes.push(m.data); waiters.splice(0).forEach((w) => w()); });
const waitEcho = (pred, ms) => within(ms, "echo", (res) => {
  const look = () => { const e = echoes.find(pred); if (e) res(e); else waiters.push(look); };
  look();
});
const fromWeb = new Topic({ ros, name: "/from_web", messageType: "std_msgs/String" });
fromWeb.advertise();
await check("publish, rospy echoes it", async () => {
  // again and again until rospy's subscriber has connected to the server's new publisher
  const tick = setInterval(() => fromWeb.publish({ data: "hi from roslib" }), 200);
  try {
    return [true, await waitEcho((d) => d === "rospy got: hi from roslib", 20000)];
  } finally { clearInterval(tick); }
});

await check("callService", async () => {
  const s = new Service({ ros, name: "/set_flag", serviceType: "std_srvs/SetBool" });
  const r = await within(10000, "set_flag", (res, rej) => s.callService({ data: true }, res, rej));
  return [r.success === true && r.message === "flag=True", r];
});
await check("callService, a missing service fails", async () => {
  const s = new Service({ ros, name: "/no_such_service", serviceType: "std_srvs/SetBool" });
  try {
    const r = await within(10000, "missing", (res, rej) => s.callService({ data: true }, res, rej));
    return [false, r];
  } catch (e) { return [e.message === "Service /no_such_service does not exist", e.message]; }
});

await check("advertise a service, rospy calls it", async () => {
  const s = new Service({ ros, name: "/web_setbool", serviceType: "std_srvs/SetBool" });
  await s.advertise((req, resp) => { resp.success = req.data; resp.message = "web says ok"; return true; });
  fromWeb.publish({ data: "call /web_setbool" });
  const e = await waitEcho((d) => d.startsWith("web service"), 40000);
  s.unadvertise();
  return [e === "web service said: web says ok", e];
});

const failed = results.filter((r) => !r.ok).length;
console.log(JSON.stringify({ summary: true, passed: results.length - failed, failed }));
ros.close();
setTimeout(() => process.exit(failed ? 1 : 0), 200);
