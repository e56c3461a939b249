"use strict";
// A scripted session on a large log (browser tests): the page holds the names only, the
// tree shows a bounded number of rows, the filter finds a variable, and a plotted signal
// arrives decimated to the plot's width, then at full resolution when zoomed.
(async () => {
  const app = window.app;
  const checks = [];
  const check = (what, ok, detail = "") => checks.push({what, ok: !!ok, detail: String(detail)});
  const sleep = ms => new Promise(r => setTimeout(r, ms));
  const waitFor = async (cond, what, ms = 20000) => {
    for (let t = 0; t < ms; t += 50) { if (cond()) return true; await sleep(50); }
    check(`waited for ${what}`, false, "timed out");
    return false;
  };
  try {
    await app.ready;
    const run = app.state.active;
    const v = app.state.vars[run];
    check("every name is listed", v.names.length === 10000, v.names.length);
    const rows = document.querySelectorAll("#tree > .row").length;
    check("the tree shows a bounded number of rows", rows <= 300 && document.querySelector("#tree .more"), rows);
    const filter = document.querySelector("#filter");
    filter.value = "part777.";
    filter.dispatchEvent(new Event("input"));
    const leaves = document.querySelectorAll("#tree .leaf");
    check("the filter finds the variables", leaves.length === 10, leaves.length);
    document.querySelector('#tree .leaf[data-name="part777.sub3.x"]').click();
    await waitFor(() => app.state.data[`${run}|part777.sub3.x`], "the signal");
    const d = app.state.data[`${run}|part777.sub3.x`];
    const width = app.plot.plotWidth();
    check("signal decimated to the plot width", d.decimated && d.t.length <= 2 * (width + 2), `${d.t.length} points, ${width} px`);
    app.plot.setView([0.5, 0.51]);
    await waitFor(() => { const z = app.state.data[`${run}|part777.sub3.x`]; return z && z.t[0] >= 0.49; }, "the zoom");
    const z = app.state.data[`${run}|part777.sub3.x`];
    check("zoomed window at full resolution", !z.decimated && z.t.length === z.n_window, `${z.t.length} of ${z.n_window}`);
    check("one curve drawn", document.querySelectorAll("#plot polyline.trace").length === 1);
  } catch (err) {
    check("scenario ran to the end", false, `${err.message}\n${err.stack}`);
  }
  await fetch("/api/scenario", {method: "POST", headers: {"Content-Type": "application/json"},
                                body: JSON.stringify({checks, address: location.search})});
  document.title = "scenario done";
})();
