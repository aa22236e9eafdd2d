// Parses an episode the way Foxglove Studio does, with Foxglove Studio's own code.
//
//   node check_episode.mjs EPISODE.mcap LAYOUT.json SCHEMAS.json
//   node check_episode.mjs - - SCHEMAS.json       (the schemas only)
//
// The parsers are packages/mcap-support/src/{parseJsonSchema,protobufDefinitionsToDatatypes,
// parseChannel}.ts of the open-source Foxglove Studio (MPL-2.0), as published, compiled, in
// the npm package @foxglove/studio-base 1.48.0 (pinned with its integrity in
// package-lock.json). Lichtblick, the maintained fork of this code, publishes no npm package
// holding its mcap-support (no @lichtblick/mcap-support; @lichtblick/suite is the extension
// API only), so the published Studio build is the pinned copy of that parser here.
// The package is a webpack build, so this script takes the three modules'
// text out of the bundle, as webpack concatenated them, and runs it with the libraries they
// import (protobufjs and its descriptor extension, @protobufjs/base64) from npm.
//
// For every channel of the episode: parseChannel must accept the channel (schema and
// encoding), and its deserializer must decode every message. For every path a Plot panel of
// the layout plots (TOPIC.FIELD or TOPIC.FIELD[I]), the parsed datatype must be a number
// type, and each message's value must be a finite number, or absent (an absent value: no
// point); at least one message must have it. For every path of a State Transitions panel,
// the value must be a string or a number in every message. Every JSON schema in SCHEMAS.json
// (name -> schema, the writer's whole table) must parse with parseJsonSchema too.
//
// Prints one JSON object (the counts per topic, the problems found) and exits 1 on any
// problem.

import { readFileSync, readdirSync } from "node:fs";
import { createRequire } from "node:module";
import path from "node:path";

import { McapStreamReader } from "@mcap/core";
import { decompress as zstdDecompress } from "fzstd";

const require = createRequire(import.meta.url);

function loadFoxgloveParsers() {
  const assets = path.join(
    path.dirname(require.resolve("@foxglove/studio-base/package.json")),
    "assets",
  );
  const marker = ";// CONCATENATED MODULE: ../mcap-support/src/parseChannel.ts";
  const file = readdirSync(assets)
    .filter((name) => name.endsWith(".js"))
    .map((name) => path.join(assets, name))
    .find((candidate) => readFileSync(candidate, "utf8").includes(marker));
  if (file === undefined) {
    throw new Error(`@foxglove/studio-base: no bundle in ${assets} holds ${marker}`);
  }
  const bundle = readFileSync(file, "utf8");
  const section = (name) => {
    const start = bundle.indexOf(`;// CONCATENATED MODULE: ../mcap-support/src/${name}.ts`);
    if (start < 0) {
      throw new Error(`${file}: no module ${name}`);
    }
    const rest = bundle.slice(start + 10);
    const ends = [";// CONCATENATED MODULE:", "// EXTERNAL MODULE:"]
      .map((m) => rest.indexOf(m))
      .filter((i) => i >= 0);
    return bundle.slice(start, start + 10 + Math.min(...ends));
  };
  const code = [
    section("parseJsonSchema"),
    section("protobufDefinitionsToDatatypes"),
    section("parseChannel"),
    "return { parseChannel, parseJsonSchema };",
  ].join("\n");
  const protobufjs = require("protobufjs");
  const unsupported = (what) => () => {
    throw new Error(`${what} is not loaded in this check`);
  };
  // The names the bundle gives the modules these three import (its EXTERNAL MODULE lines).
  const imports = {
    base64: require("@protobufjs/base64"),
    protobufjs_default: () => protobufjs,
    descriptor: require("protobufjs/ext/descriptor"),
    dist: { parse: unsupported("ros1msg"), parseRos2idl: unsupported("ros2idl") },
    esm: { MessageReader: unsupported("ros1") },
    rosmsg2_serialization_dist: { MessageReader: unsupported("cdr") },
    parseFlatbufferSchema: unsupported("flatbuffer"),
  };
  const factory = new Function(...Object.keys(imports), code);
  return { ...factory(...Object.values(imports)), source: file };
}

function readEpisode(file) {
  const reader = new McapStreamReader({
    decompressHandlers: { zstd: (data, size) => zstdDecompress(data, new Uint8Array(Number(size))) },
    validateCrcs: true,
  });
  reader.append(readFileSync(file));
  const schemas = new Map();
  const channels = new Map();
  const messages = [];
  for (let record; (record = reader.nextRecord()) !== undefined; ) {
    if (record.type === "Schema") schemas.set(record.id, record);
    else if (record.type === "Channel") channels.set(record.id, record);
    else if (record.type === "Message") messages.push(record);
  }
  if (!reader.done()) {
    throw new Error(`${file}: the MCAP file does not end with its footer`);
  }
  return { schemas, channels, messages };
}

function layoutPaths(node, kind, out = []) {
  if (Array.isArray(node)) {
    node.forEach((item) => layoutPaths(item, kind, out));
  } else if (node !== null && typeof node === "object") {
    for (const [key, value] of Object.entries(node)) {
      if (key === "paths" && Array.isArray(value)) {
        out.push(...value.map((p) => ({ kind, value: p.value })));
      } else {
        layoutPaths(value, kind, out);
      }
    }
  }
  return out;
}

function main() {
  const [episodeFile, layoutFile, schemasFile] = process.argv.slice(2);
  const { parseChannel, parseJsonSchema, source } = loadFoxgloveParsers();
  const problems = [];
  const report = { parser: source, channels: {}, plotted: {}, schemas: 0, problems };

  for (const [name, schema] of Object.entries(JSON.parse(readFileSync(schemasFile, "utf8")))) {
    try {
      parseJsonSchema(schema, name);
      report.schemas += 1;
    } catch (error) {
      problems.push(`schema ${name}: ${error.message}`);
    }
  }

  if (episodeFile === "-") {
    console.log(JSON.stringify(report, null, 1));
    process.exit(problems.length === 0 ? 0 : 1);
  }
  const { schemas, channels, messages } = readEpisode(episodeFile);
  const decoded = new Map(); // topic -> [value]
  const datatypesOf = new Map(); // topic -> { root, datatypes }
  for (const channel of channels.values()) {
    const schema = schemas.get(channel.schemaId);
    let parsed;
    try {
      parsed = parseChannel({
        messageEncoding: channel.messageEncoding,
        schema: schema && { name: schema.name, encoding: schema.encoding, data: schema.data },
      });
    } catch (error) {
      problems.push(`channel ${channel.topic}: ${error.message}`);
      continue;
    }
    datatypesOf.set(channel.topic, { root: schema?.name, datatypes: parsed.datatypes });
    const values = [];
    for (const message of messages) {
      if (message.channelId !== channel.id) continue;
      try {
        values.push(parsed.deserialize(message.data));
      } catch (error) {
        problems.push(`channel ${channel.topic}: a message does not decode: ${error.message}`);
        break;
      }
    }
    decoded.set(channel.topic, values);
    report.channels[channel.topic] = values.length;
  }

  const layout = JSON.parse(readFileSync(layoutFile, "utf8")).configById;
  const wanted = [];
  for (const [id, config] of Object.entries(layout)) {
    const kind = id.split("!")[0];
    if (kind === "Plot" || kind === "StateTransitions") layoutPaths(config, kind, wanted);
  }
  for (const { kind, value } of wanted) {
    const match = /^(\/[\w/]+)\.(\w+)(?:\[(\d+)\])?$/.exec(value);
    if (match === null) {
      problems.push(`layout path ${value}: not TOPIC.FIELD or TOPIC.FIELD[I]`);
      continue;
    }
    const [, topic, field, index] = match;
    const values = decoded.get(topic);
    if (values === undefined || values.length === 0) {
      problems.push(`layout path ${value}: the episode has no decoded ${topic} message`);
      continue;
    }
    const { root, datatypes } = datatypesOf.get(topic);
    const definition = datatypes.get(root)?.definitions.find((d) => d.name === field);
    let present = 0;
    let absent = 0;
    const bad = [];
    for (const message of values) {
      let v = message[field];
      if (index !== undefined && v !== undefined) v = v[Number(index)];
      if (v === undefined) {
        absent += 1;
      } else if (kind === "Plot" ? typeof v === "number" && Number.isFinite(v)
                                 : typeof v === "string" || typeof v === "number") {
        present += 1;
      } else {
        bad.push(JSON.stringify(v));
      }
    }
    report.plotted[value] = { kind, type: definition?.type, present, absent };
    if (definition === undefined) {
      problems.push(`layout path ${value}: ${root} has no field ${field}`);
    } else if (kind === "Plot" && !["float64", "float32", "int32", "uint32"].includes(definition.type)) {
      problems.push(`layout path ${value}: parsed as ${definition.type}, not a number`);
    }
    if (bad.length > 0) {
      problems.push(`layout path ${value}: ${bad.length} values not a ${kind === "Plot" ? "finite number" : "string"}, e.g. ${bad[0]}`);
    }
    if (present === 0 || (kind === "StateTransitions" && absent > 0)) {
      problems.push(`layout path ${value}: ${present} messages with a value, ${absent} without`);
    }
  }

  console.log(JSON.stringify(report, null, 1));
  process.exit(problems.length === 0 ? 0 : 1);
}

main();
