// A FoxgloveClient of @foxglove/ws-protocol 0.8.0 on `ws`, driven by JSON commands on stdin
// (one a line) and printing every event as one JSON line on stdout.
//
// usage: node foxglove-client.mjs URL [SUBPROTOCOL]
// commands: {"do":"subscribe","topic":T} {"do":"unsubscribe","topic":T}
//   {"do":"advertise","topic":T,"encoding":"ros1","schemaName":N,"schema":S}
//   {"do":"publish","topic":T,"data":BASE64} {"do":"callService","service":NAME,"data":BASE64,"callId":N}
//   {"do":"getParameters","names":[..],"id":I} {"do":"setParameters","parameters":[..],"id":I}
//   {"do":"subscribeParameterUpdates","names":[..]} {"do":"subscribeConnectionGraph"} {"do":"close"}
import wsProtocol from "@foxglove/ws-protocol";
import readline from "node:readline";
import WebSocket from "ws";

const { FoxgloveClient } = wsProtocol; // a CommonJS package: its names hang off the default

const [url, subprotocol] = [process.argv[2], process.argv[3] || FoxgloveClient.SUPPORTED_SUBPROTOCOL];
const say = (event) => process.stdout.write(JSON.stringify(event) + "\n");
const b64 = (view) => Buffer.from(view.buffer, view.byteOffset, view.byteLength).toString("base64");

const ws = new WebSocket(url, [subprotocol]);
const client = new FoxgloveClient({ ws });
const channels = new Map(); // topic -> channel
const services = new Map(); // name -> service
const subscriptions = new Map(); // topic -> subscription id
const topicOf = new Map(); // subscription id -> topic
const published = new Map(); // topic -> client channel id

client.on("open", () => say({ event: "open", protocol: ws.protocol }));
client.on("error", (err) => say({ event: "error", message: String(err && err.message) }));
client.on("close", () => { say({ event: "close" }); process.exit(0); });
client.on("serverInfo", (info) => say({ event: "serverInfo", ...info }));
client.on("status", (status) => say({ event: "status", ...status }));
client.on("advertise", (list) => {
  for (const c of list) channels.set(c.topic, c);
  say({ event: "advertise", channels: list });
});
client.on("unadvertise", (ids) => say({ event: "unadvertise", channelIds: ids }));
client.on("advertiseServices", (list) => {
  for (const s of list) services.set(s.name, s);
  say({ event: "advertiseServices", services: list });
});
client.on("message", ({ subscriptionId, timestamp, data }) =>
  say({ event: "message", topic: topicOf.get(subscriptionId), subscriptionId, timestamp: String(timestamp), data: b64(data) }));
client.on("time", ({ timestamp }) => say({ event: "time", timestamp: String(timestamp) }));
client.on("parameterValues", (values) => say({ event: "parameterValues", ...values }));
client.on("serviceCallResponse", (r) =>
  say({ event: "serviceCallResponse", serviceId: r.serviceId, callId: r.callId, encoding: r.encoding, data: b64(r.data) }));
client.on("serviceCallFailure", (f) => say({ event: "serviceCallFailure", ...f }));
client.on("connectionGraphUpdate", (u) => say({ event: "connectionGraphUpdate", ...u }));

const commands = {
  subscribe: ({ topic }) => {
    const id = client.subscribe(channels.get(topic).id);
    subscriptions.set(topic, id);
    topicOf.set(id, topic);
  },
  unsubscribe: ({ topic }) => client.unsubscribe(subscriptions.get(topic)),
  advertise: ({ topic, encoding, schemaName, schema }) =>
    published.set(topic, client.advertise({ topic, encoding, schemaName, schema, schemaEncoding: "ros1msg" })),
  publish: ({ topic, data }) => client.sendMessage(published.get(topic), new Uint8Array(Buffer.from(data, "base64"))),
  callService: ({ service, data, callId }) => client.sendServiceCallRequest({
    serviceId: services.get(service).id, callId, encoding: "ros1", data: new DataView(Uint8Array.from(Buffer.from(data, "base64")).buffer),
  }),
  getParameters: ({ names, id }) => client.getParameters(names, id),
  setParameters: ({ parameters, id }) => client.setParameters(parameters, id),
  subscribeParameterUpdates: ({ names }) => client.subscribeParameterUpdates(names),
  subscribeConnectionGraph: () => client.subscribeConnectionGraph(),
  close: () => client.close(),
};

readline.createInterface({ input: process.stdin }).on("line", (line) => {
  try {
    const command = JSON.parse(line);
    commands[command.do](command);
  } catch (err) {
    say({ event: "error", message: `command ${line}: ${err.message}` });
  }
});
