// Run a GLSL function of a client's shader source in node, one colour channel at a time.
// Only what these functions use is handled: #ifdef/#ifndef/#else/#endif, `float`/`vec3`
// declarations (become `let`), scalar arithmetic. Anything else throws, so a changed shader
// fails the test instead of being evaluated wrongly.

export function preprocess(source, defines) {
  const out = [];
  const stack = [];
  const active = () => stack.every((s) => s.on);
  for (const line of source.split("\n")) {
    const t = line.trim();
    let m;
    if ((m = t.match(/^#ifdef\s+(\w+)$/))) stack.push({ on: defines.has(m[1]), seen: defines.has(m[1]) });
    else if ((m = t.match(/^#ifndef\s+(\w+)$/))) stack.push({ on: !defines.has(m[1]), seen: !defines.has(m[1]) });
    else if (t === "#else") { const s = stack[stack.length - 1]; s.on = !s.seen; }
    else if (t === "#endif") stack.pop();
    else if (t.startsWith("#")) throw new Error(`unsupported directive: ${t}`);
    else if (active()) out.push(line);
  }
  if (stack.length) throw new Error("unbalanced #if");
  return out.join("\n");
}

export function functionBody(source, name) {
  const head = new RegExp(`vec3\\s+${name}\\s*\\(([^)]*)\\)\\s*\\{`);
  const m = source.match(head);
  if (!m) throw new Error(`no function ${name} in the shader source`);
  let depth = 1;
  let i = m.index + m[0].length;
  const start = i;
  for (; depth > 0; i++) {
    if (source[i] === "{") depth++;
    else if (source[i] === "}") depth--;
  }
  return { params: m[1], body: source.slice(start, i - 1) };
}

// A JS function (one channel) of the GLSL function `name`: arguments are the GLSL parameters
// (vectors as {x, y, z}, vec3 arrays as arrays of numbers) followed by `uniforms` by name.
export function channelFunction(source, name, uniforms = []) {
  const { params, body } = functionBody(source, name);
  const names = params.split(",").map((p) => p.replace(/\[[^\]]*\]/, "").trim().split(/\s+/).pop());
  const js = body
    .replace(/\/\/.*$/gm, "")
    .replace(/\b(?:float|vec3)\s+(?=\w+\s*=)/g, "let ");
  if (/\b(vec[234]|mat[234]|float|int)\b/.test(js)) throw new Error(`cannot run: ${js}`);
  return new Function(...names, ...uniforms, js);
}
