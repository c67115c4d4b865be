#!/bin/sh
# bench/povray.sh - portray against POV-Ray 3.7 on the same scenes, like for
# like: the shared SPD scenes with their POV-Ray twins
# ($PORTRAY_SHARED/spd/pov/NAME.twin.pov), and the teapot and dragon meshes
# ($PORTRAY_SHARED/meshes, each on its floor as in teapot.sce), whose twins
# this script writes (a POV-Ray mesh of smooth triangles with welded,
# angle-weighted vertex normals, as portray's `smooth`; same camera, lights
# and finishes).
#
# Three modes, each at POV_W x POV_H (default 1280x960) on POV_THREADS threads
# (default 1; "1 2" for both):
#   plain  one eye ray per pixel: ours `filter standard`, POV-Ray -A;
#   deep   plain, with POV-Ray tracing as deep as portray: the twin's
#          global_settings get max_trace_level 11 and adc_bailout 1/512
#          (portray traces 10 bounces, LIM_TRACE_DEPTH, and no ray whose
#          weight is below 1/512, SHADE_MIN_WEIGHT; POV-Ray's defaults, 5
#          levels counting the eye ray and 1/255, stop sooner);
#   ss3    a fixed 3x3 grid in every pixel: ours `filter super-sample
#          x-samples 3 y-samples 3`, POV-Ray +AM1 +A0.0 +R3 (threshold 0:
#          every pixel that differs at all from a neighbour, i.e. nearly
#          all, gets the 3x3 grid on top of its first ray).
# Eye rays are counted on both sides (ours: the summary's "eye rays"; POV-Ray:
# "Pixels" + "Samples" of its statistics) and printed per pixel; "ratio/ray"
# divides each program's time by its own eye rays, so it is the ratio at
# equal eye rays per pixel when the counts differ (POV-Ray traces about 10
# per pixel in ss3: its first ray and the 9 of the grid). Secondary rays
# (mirror and transmitted, every depth; shadow rays not counted) are
# printed per pixel too: ours the summary's "secondary rays", POV-Ray's its
# "Reflected", "Refracted" and "Transmitted Rays" less the "Saved" ones
# (POV-Ray 3.7 counts a ray before its weight test drops it, and before its
# trace-level test: where its "Max Level" reached the limit, some counted
# rays were not traced, and its figure is marked "+").
#
# Times are of the whole process (start-up, parsing, building, tracing and
# writing the PNG), measured by build/tools/cputime (to the microsecond;
# /usr/bin/time, to the hundredth of a second, where that is not built:
# 8-20% of a tetra_s4 or teapot render): CPU time (user + system,
# every thread the process ran; the figure that holds on a shared machine,
# and POV-Ray's start-up waits about 0.6 s without using the CPU) and
# wall-clock time. POV-Ray and portray run alternately, POV_REPS times each
# (default 2), in one run; the best of each is compared.
# ratio = portray / POV-Ray (below 1: portray is faster). Targets of issue
# 13: plain CPU ratio <= 0.20 and ss3 ratio/ray <= 0.33 at 1 thread.
#
# POV_SCENES="balls_s4 teapot" limits the scenes, POV_MODES=plain (deep,
# ss3) the modes (default "plain deep ss3"). Skips (exit 0) when povray,
# both timers or the shared data is missing. Nothing here is a test.
SHARED=${PORTRAY_SHARED:-../shared/data}
MASTER=${MASTER:-bin/portray-master}
W=${POV_W:-1280}
H=${POV_H:-960}
REPS=${POV_REPS:-2}
THREADS=${POV_THREADS:-1}
MODES=${POV_MODES:-plain deep ss3}
if ! command -v povray >/dev/null 2>&1; then
	echo "povray not installed: skipped"
	exit 0
fi
# timed COMMAND...: COMMAND, then "TIME user sys wall" (seconds) on stderr
CPUTIME=${CPUTIME:-build/tools/cputime}
if [ -x "$CPUTIME" ]; then
	CPUTIME=$(cd "$(dirname "$CPUTIME")" && pwd)/$(basename "$CPUTIME")
	timed() { "$CPUTIME" "$@"; }
elif [ -x /usr/bin/time ]; then
	timed() { /usr/bin/time -f "TIME %U %S %e" "$@"; }
else
	echo "neither $CPUTIME nor /usr/bin/time: skipped"
	exit 0
fi
if [ ! -d "$SHARED/spd/pov" ] && [ ! -d "$SHARED/meshes" ]; then
	echo "no shared data ($SHARED): skipped"
	exit 0
fi
if [ ! -x "$MASTER" ]; then
	echo "$MASTER not built: skipped"
	exit 0
fi
SHARED=$(cd "$SHARED" && pwd)
TMP=$(mktemp -d "${TMPDIR:-/tmp}/portray-pov.XXXXXX")
trap 'rm -rf "$TMP"' EXIT

# mesh_twins NAME RAW: writes $TMP/NAME.sce (teapot.sce's scene over RAW)
# and $TMP/NAME.pov (its POV-Ray twin)
mesh_twins() {
	sed "s#file teapot.raw#file $2#" "$SHARED/meshes/teapot.sce" >"$TMP/$1.sce"
	awk '
	function unit(v, w,   m) {
		m = sqrt(v[1] * v[1] + v[2] * v[2] + v[3] * v[3])
		if (m > 0) { w[1] = v[1] / m; w[2] = v[2] / m; w[3] = v[3] / m }
		else { w[1] = 0; w[2] = 0; w[3] = 0 }
	}
	function cross(a, b, c) {
		c[1] = a[2] * b[3] - a[3] * b[2]
		c[2] = a[3] * b[1] - a[1] * b[3]
		c[3] = a[1] * b[2] - a[2] * b[1]
	}
	function vid(x, y, z,   k) {
		k = x " " y " " z
		if (!(k in id)) {
			id[k] = ++nv
			px[nv] = x; py[nv] = y; pz[nv] = z
		}
		return id[k]
	}
	NF == 9 {
		nt++
		for (k = 0; k < 3; k++)
			t[nt, k] = vid($(3 * k + 1) + 0, $(3 * k + 2) + 0, $(3 * k + 3) + 0)
	}
	END {
		for (i = 1; i <= nt; i++) {
			for (k = 0; k < 3; k++) {
				a = t[i, k]; b = t[i, (k + 1) % 3]; c = t[i, (k + 2) % 3]
				e1[1] = px[b] - px[a]; e1[2] = py[b] - py[a]; e1[3] = pz[b] - pz[a]
				e2[1] = px[c] - px[a]; e2[2] = py[c] - py[a]; e2[3] = pz[c] - pz[a]
				unit(e1, u1); unit(e2, u2)
				cross(u1, u2, f)
				s = sqrt(f[1] * f[1] + f[2] * f[2] + f[3] * f[3])
				if (s == 0)
					continue
				ang = atan2(s, u1[1] * u2[1] + u1[2] * u2[2] + u1[3] * u2[3])
				nx[a] += f[1] / s * ang; ny[a] += f[2] / s * ang; nz[a] += f[3] / s * ang
			}
		}
		print "// POV-Ray twin of teapot.sce over a RAW mesh, written by bench/povray.sh"
		print "background { color rgb <0, 0, 0> }"
		print "#declare floor_mat = material { texture { pigment { color rgb <0.55, 0.55, 0.55> } finish { ambient 0 diffuse 0.8 } } }"
		print "#declare mesh_mat = material { texture { pigment { color rgb <0.8, 0.3, 0.25> } finish { ambient 0 diffuse 0.8 phong 0.3 phong_size 40 } } }"
		print "plane { <0, 1, 0>, 0 material { floor_mat } }"
		print "mesh {"
		for (i = 1; i <= nt; i++) {
			line = "  smooth_triangle {"
			for (k = 0; k < 3; k++) {
				v = t[i, k]
				m = sqrt(nx[v] * nx[v] + ny[v] * ny[v] + nz[v] * nz[v])
				if (m > 0) { ax = nx[v] / m; ay = ny[v] / m; az = nz[v] / m } else { ax = 0; ay = 0; az = 1 }
				line = line sprintf("%s <%.9g, %.9g, %.9g>, <%.9g, %.9g, %.9g>", k ? "," : "", px[v], py[v], pz[v], ax, ay, az)
			}
			print line " }"
		}
		print "  material { mesh_mat }"
		print "}"
	}' "$2" >"$TMP/$1.body.pov"
	# camera and lights from teapot.sce: right = unit(drop x view) * x-size,
	# up = unit(right x view) * y-size, direction = unit(view) * depth, as
	# portray's camera; the second light has no shadows
	awk '
	function num(s) { gsub(/[()]/, "", s); return s + 0 }
	/look-from/ { fx = num($2); fy = num($3); fz = num($4) }
	/look-at/ { ax = num($2); ay = num($3); az = num($4) }
	/drop-line/ { dx = num($2); dy = num($3); dz = num($4) }
	/^ *depth/ { dep = $2 }
	/x-size/ { xs = $2 }
	/y-size/ { ys = $2 }
	END {
		vx = ax - fx; vy = ay - fy; vz = az - fz
		m = sqrt(vx * vx + vy * vy + vz * vz); vx /= m; vy /= m; vz /= m
		rx = dy * vz - dz * vy; ry = dz * vx - dx * vz; rz = dx * vy - dy * vx
		m = sqrt(rx * rx + ry * ry + rz * rz); rx /= m; ry /= m; rz /= m
		ux = ry * vz - rz * vy; uy = rz * vx - rx * vz; uz = rx * vy - ry * vx
		m = sqrt(ux * ux + uy * uy + uz * uz); ux /= m; uy /= m; uz /= m
		printf "camera {\n  location <%.9g, %.9g, %.9g>\n", fx, fy, fz
		printf "  direction <%.9g, %.9g, %.9g>\n", vx * dep, vy * dep, vz * dep
		printf "  right <%.9g, %.9g, %.9g>\n", rx * xs, ry * xs, rz * xs
		printf "  up <%.9g, %.9g, %.9g>\n}\n", ux * ys, uy * ys, uz * ys
	}' "$TMP/$1.sce" >"$TMP/$1.pov"
	awk '
	function num(s) { gsub(/[()]/, "", s); return s + 0 }
	/^light/ { inl = 1; shadowless = ""; next }
	inl && /colour/ { cr = num($2); cg = num($3); cb = num($4) }
	inl && /position/ { lx = num($2); ly = num($3); lz = num($4) }
	inl && /no-shadows/ { shadowless = " shadowless" }
	inl && /^;/ {
		printf "light_source { <%s, %s, %s> color rgb <%s, %s, %s>%s }\n", lx, ly, lz, cr, cg, cb, shadowless
		inl = 0
	}' "$TMP/$1.sce" >>"$TMP/$1.pov"
	cat "$TMP/$1.body.pov" >>"$TMP/$1.pov"
}

# run_pov POVFILE THREADS MODE: "cpu wall eye_rays secondary_rays" of one
# POV-Ray run
run_pov() {
	aa=-A
	[ "$3" = ss3 ] && aa="+AM1 +A0.0 +R3"
	pov=$1
	if [ "$3" = deep ]; then
		pov=$TMP/deep.pov
		{
			echo "global_settings { max_trace_level 11 adc_bailout 1/512 }"
			cat "$1"
		} >"$pov"
	fi
	# shellcheck disable=SC2086 # $aa is several options
	(cd "$TMP" && timed povray "+I$pov" "+O$TMP/pov.png" +FN "+W$W" "+H$H" -D $aa \
		"+WT$2" >"$TMP/pov.log" 2>&1)
	tr '\r' '\n' <"$TMP/pov.log" | awk '
	/^TIME/ { cpu = $2 + $3; wall = $4 }
	/^Pixels:/ { rays = $2 + $4 }
	/^Rays:/ { saved = $4; split($7, lv, "/"); cut = lv[1] == lv[2] ? "+" : "" }
	/^(Reflected|Refracted|Transmitted) Rays:/ { sec += $3 }
	END { if (cpu != "" && rays != "") print cpu, wall, rays, sec - saved, cut }'
}

# run_ours SCENE THREADS: the same for portray
run_ours() {
	timed "$MASTER" "$1" -o "$TMP/ours.png" -j "$2" --size "${W}x${H}" >"$TMP/ours.log" 2>&1
	awk '
	/^TIME/ { cpu = $2 + $3; wall = $4 }
	/eye rays/ { for (i = 1; i < NF; i++) { if ($(i + 1) == "eye") rays = $i; if ($(i + 1) == "secondary") sec = $i } }
	END { if (cpu != "" && rays != "") print cpu, wall, rays, sec + 0 }' "$TMP/ours.log"
}

# compare NAME SCENE POVFILE: every mode and thread count, interleaved
compare() {
	sed 's/filter standard/filter super-sample x-samples 3 y-samples 3/' "$2" >"$TMP/$1.ss3.sce"
	for threads in $THREADS; do
		for mode in $MODES; do
			s=$2
			[ "$mode" = ss3 ] && s=$TMP/$1.ss3.sce
			best_p="" best_o=""
			rep=0
			while [ "$rep" -lt "$REPS" ]; do
				p=$(run_pov "$3" "$threads" "$mode")
				o=$(run_ours "$s" "$threads")
				if [ -z "$p" ] || [ -z "$o" ]; then
					echo "$1 -j$threads $mode: measurement failed (povray '$p', portray '$o')"
					sed -n '1,5p' "$TMP/ours.log"
					continue 2
				fi
				best_p=$(printf '%s\n%s\n' "$best_p" "$p" | awk 'NF && (b == "" || $1 < b) { b = $1; l = $0 } END { print l }')
				best_o=$(printf '%s\n%s\n' "$best_o" "$o" | awk 'NF && (b == "" || $1 < b) { b = $1; l = $0 } END { print l }')
				rep=$((rep + 1))
			done
			echo "$best_o $best_p" | awk -v n="$1" -v t="$threads" -v m="$mode" -v px="$((W * H))" '{
				printf "%-9s -j%d %-5s portray cpu %7.3f s wall %7.3f s %5.2f rays/px %5.3f sec/px | povray cpu %7.3f s wall %7.3f s %5.2f rays/px %5.3f%1s sec/px | ratio cpu %.3f wall %.3f ratio/ray %.3f\n",
					n, t, m, $1, $2, $3 / px, $4 / px, $5, $6, $7 / px, $8 / px, $9, $1 / $5, $2 / $6, ($1 / $3) / ($5 / $7)
			}'
		done
	done
}

want() {
	[ -z "${POV_SCENES:-}" ] && return 0
	case " $POV_SCENES " in *" $1 "*) return 0 ;; esac
	return 1
}

echo "# ${W}x${H}, whole process, best of $REPS interleaved runs; ratio = portray / POV-Ray"
for pov in "$SHARED"/spd/pov/*.twin.pov; do
	[ -f "$pov" ] || continue
	name=$(basename "$pov" .twin.pov)
	want "$name" || continue
	sce=$SHARED/spd/$name.sce
	[ -f "$sce" ] || sce=tests/data/spd/$name.sce
	[ -f "$sce" ] || continue
	compare "$name" "$sce" "$pov"
done
for mesh in teapot dragon; do
	raw=$SHARED/meshes/$mesh.raw
	[ -f "$raw" ] && [ -f "$SHARED/meshes/teapot.sce" ] || continue
	want "$mesh" || continue
	mesh_twins "$mesh" "$raw"
	compare "$mesh" "$TMP/$mesh.sce" "$TMP/$mesh.pov"
done
