"use strict";
// A scripted session of the explorer, run by the browser tests (tests/explore): opened as
// /?scenario=basic&csv=PATH, it clicks through the page as a user would and posts what it
// saw to /api/scenario. Each check compares with physics (the DC motor is linear, its
// final speed is k V / (R B + k^2)), not with numbers recorded from an earlier run.
(async () => {
  const app = window.app;
  const q = new URLSearchParams(location.search);
  const checks = [];
  const check = (what, ok, detail = "") => checks.push({what, ok: !!ok, detail: String(detail)});
  const sleep = ms => new Promise(r => setTimeout(r, ms));
  const waitFor = async (cond, what, ms = 20000) => {
    for (let t = 0; t < ms; t += 50) { if (cond()) return true; await sleep(50); }
    check(`waited for ${what}`, false, "timed out");
    return false;
  };
  const last = d => d.y[d.y.length - 1];
  const data = (run, name) => app.state.data[`${run}|${name}`];
  const fire = (input, value) => { input.value = value; input.dispatchEvent(new Event("change")); };
  const report = {checks};
  try {
    await app.ready;
    // 1. open a model: description, parameters, diagram
    app.showView("models");
    await app.loadModel("dc_motor");
    check("model page shows the diagram", document.querySelector("#diagram svg"));
    check("model page lists the 6 parameters", document.querySelectorAll("#model table.data")[0].rows.length === 7);
    // 2. simulate it, then plot two signals by clicking the tree
    const run = await app.simulateModel("dc_motor", "acausal");
    document.querySelector("#clear").click();
    document.querySelector('#tree [data-node="inertia"]').click();
    document.querySelector('#tree .leaf[data-name="inertia.w"]').click();
    document.querySelector('#tree [data-node="inductor"]').click();
    document.querySelector('#tree .leaf[data-name="inductor.i"]').click();
    await waitFor(() => data(run.id, "inertia.w") && data(run.id, "inductor.i"), "two signals");
    check("two signals plotted", document.querySelectorAll("#plot polyline.trace").length === 2,
          document.querySelectorAll("#plot polyline.trace").length);
    const before = document.querySelector("#plot svg").textContent;   // tick labels
    const w1 = last(data(run.id, "inertia.w"));
    const k = 0.151, R = 7.1, B = 1.236e-4;
    check("final speed is k V / (R B + k^2)", Math.abs(w1 / (k * 19.2 / (R * B + k * k)) - 1) < 1e-4, w1);
    // 3. change a parameter: the plot changes (linear model: half the voltage, half the speed)
    fire(document.querySelector('#params input[data-path="source.V"]'), "9.6 V");
    await waitFor(() => app.runById(run.id).params["source.V"] === 9.6 && data(run.id, "inertia.w") &&
                        Math.abs(last(data(run.id, "inertia.w")) - w1) > 1, "the re-simulation");
    const w2 = last(data(run.id, "inertia.w"));
    check("half the voltage gives half the speed", Math.abs(w2 / w1 - 0.5) < 1e-4, w2 / w1);
    check("the plot was redrawn (new axis ticks)", document.querySelector("#plot svg").textContent !== before);
    // 4. overlay a second run (keep the first, double the resistance)
    document.querySelector("#keep-run").checked = true;
    fire(document.querySelector('#params input[data-path="resistor.R"]'), "14.2 Ohm");
    await waitFor(() => app.state.runs.length === 2 && app.state.plotted.length === 4, "the second run");
    const run2 = app.state.runs[1];
    document.querySelector("#overlay").click();
    await waitFor(() => data(run2.id, "inertia.w"), "the overlay");
    const w3 = last(data(run2.id, "inertia.w"));
    check("second run: final speed with R = 14.2 Ohm, V = 9.6 V", Math.abs(w3 / (k * 9.6 / (14.2 * B + k * k)) - 1) < 1e-4, w3);
    check("both runs drawn", document.querySelectorAll('#plot polyline[data-key$="|inertia.w"]').length === 2);
    app.plot.showCursor(0.25);
    const diffs = [...document.querySelectorAll("#readout tr")].map(tr => tr.cells[5] && tr.cells[5].textContent).filter(Boolean);
    check("readout shows the difference between runs", diffs.length >= 2, diffs.join(" "));
    // differences: the second run drawn as its difference to the first, on its own axis
    document.querySelector("#diff").click();
    await waitFor(() => data(run2.id, "inertia.w") && data(run2.id, "inertia.w").minus === run.id, "the differences");
    const d = data(run2.id, "inertia.w");
    check("difference to the first run at t_stop", Math.abs(last(d) - (w3 - w2)) < 1e-6 * w2, `${last(d)} vs ${w3 - w2}`);
    check("differences on their own axis", [...document.querySelectorAll("#plot text")].some(t => t.textContent === "[Δ rad/s]"));
    document.querySelector("#diff").click();
    await waitFor(() => !data(run2.id, "inertia.w").minus, "absolute values again");
    // 5. load a measurement (CSV) and overlay it
    if (q.get("csv")) {
      const measured = await app.openPath(q.get("csv"));
      document.querySelector("#overlay").click();
      await waitFor(() => data(measured.id, "inertia.w"), "the measurement");
      check("measurement overlaid", document.querySelectorAll('#plot polyline[data-key$="|inertia.w"]').length === 3);
      // an uploaded file (what the file chooser sends) loads the same way
      const text = await (await fetch(`/api/runs/${run.id}/export?name=inertia.w&format=csv`)).text();
      const up = await app.upload(new File([text], "exported.csv"));
      check("uploaded CSV has the exported variable", app.state.vars[up.id].names.join() === "inertia.w");
    }
    // 6. zoom: by dragging across the plot (a quarter to a half of its width), the wheel,
    // a double-click; then to the first 10 ms, where every sample comes back
    const figure = document.querySelector("#plot svg");
    const box = figure.getBoundingClientRect();
    const x0 = app.plot.x0, x1 = app.plot.x1;
    const at = f => ({clientX: box.left + x0 + f * (x1 - x0), clientY: box.top + 120, bubbles: true, button: 0});
    const [a0, b0] = app.plot.range();
    figure.dispatchEvent(new MouseEvent("mousedown", at(0.25)));
    figure.dispatchEvent(new MouseEvent("mousemove", at(0.5)));
    figure.dispatchEvent(new MouseEvent("mouseup", at(0.5)));
    const dragged = app.plot.view;
    check("dragging zooms to the dragged span", dragged && Math.abs(dragged[0] - (a0 + 0.25 * (b0 - a0))) < 1e-3 * (b0 - a0) &&
          Math.abs(dragged[1] - (a0 + 0.5 * (b0 - a0))) < 1e-3 * (b0 - a0), JSON.stringify(dragged));
    document.querySelector("#plot svg").dispatchEvent(new WheelEvent("wheel", {...at(0.5), deltaY: -100, cancelable: true}));
    const wheeled = app.plot.view;
    check("the wheel zooms in around the cursor", wheeled && wheeled[1] - wheeled[0] < 0.81 * (dragged[1] - dragged[0]), JSON.stringify(wheeled));
    document.querySelector("#plot svg").dispatchEvent(new MouseEvent("dblclick", {bubbles: true}));
    check("double-click resets the zoom", app.plot.view === null);
    app.plot.setView([0, 0.01]);
    await waitFor(() => { const d = data(run.id, "inertia.w"); return d && d.t[d.t.length - 1] < 0.02; }, "the zoom");
    const z = data(run.id, "inertia.w");
    check("zoomed window at full resolution", !z.decimated && z.t.length === z.n_window, `${z.t.length} of ${z.n_window}`);
    // 7. a parameter of the wrong unit: a clear message, the server keeps serving
    await app.setActive(run.id);
    document.querySelector("#keep-run").checked = false;
    fire(document.querySelector('#params input[data-path="inductor.L"]'), "3 V");
    await waitFor(() => !document.querySelector("#error").hidden, "the error message");
    const message = document.querySelector("#error-text").textContent;
    check("wrong unit reported in the page", message.includes("inductor.L") && message.includes("H"), message);
    check("server still serves", (await app.api("/api/runs")).length >= 3);
    document.querySelector('#params input[data-path="inductor.L"]').value = "340 uH";
    document.querySelector("#error-close").click();
    // 8. exports
    const png = await app.exportPNG(false);
    check("PNG export", png.startsWith("data:image/png;base64,") && png.length > 5000, png.length);
    report.png = png;
    const svg = app.plot.svgText();
    check("SVG export", svg.includes("<polyline") && !svg.includes('class="overlay"'), svg.length);
    const csv = await (await fetch(`/api/runs/${run2.id}/export?name=inertia.w&name=inductor.i&format=csv&t0=0&t1=0.1`)).text();
    check("CSV export of a selection", csv.startsWith("t,inertia.w,inductor.i\n"), csv.slice(0, 40));
    // 9. the library
    app.showView("library");
    await app.loadLibrary();
    check("library lists components", document.querySelectorAll("#sections li li").length > 20);
    app.showView("results");
  } catch (err) {
    check("scenario ran to the end", false, `${err.message}\n${err.stack}`);
  }
  report.address = location.search;
  report.runs = app.state.runs;
  await fetch("/api/scenario", {method: "POST", headers: {"Content-Type": "application/json"}, body: JSON.stringify(report)});
  document.title = "scenario done";
})();
