import json, glob
tot_rows = tot_levels = tot_roots_checked = beyond = 0
for fn in sorted(glob.glob("results/speeds_*.json")):
    o = json.load(open(fn))
    if o.get("speeds_rc", 0) != 0:
        print(fn, "REFUSED:", o["speeds_stderr"][:200]); continue
    ms = o["mu_hi"]
    nb = o["n_total_bk"]
    bey = sum(1 for r in o["roots"] if str(r["status"]).startswith("skip"))
    print(fn, o["set"]["kind"], "rows", nb, "levels", o["n_levels_checked"], "extrema", [(a, round(b, 4)) for a, b in o["extrema"]],
          "checked", len(o["roots"]), "skipped", bey, "unresolved-notes", [c for c in o["bk_comments"] if "unresolved" in c][:1])
    tot_rows += nb; tot_levels += o["n_levels_checked"]; tot_roots_checked += len(o["roots"]) - bey
print("rows", tot_rows, "levels", tot_levels, "roots precisely checked", tot_roots_checked)
