/*
 * farm.c - the master's side of the farm (farm.h): the render as a whole.
 *
 * Rooms: master/sched.c decides which tile goes to whom and assembles the
 * image; master/wconn.c drives each worker's connection; here the event
 * loop (proto/evloop.h) runs them, the local threads trace on the shared
 * tile pool (common/tiles.h) from the scheduler, and progress and the
 * summary are printed.
 *
 * Every pixel is the same as a local render's: the master traces its own
 * tiles and its audits from the very scene the workers receive (the caller
 * decodes the encoded scene and builds r from it), a checksum catches
 * corruption and audits catch a worker computing wrong pixels (sched.h);
 * a worker that dies, hangs or lies costs time, never pixels.
 */
#include "master/farm.h"

#include <errno.h>
#include <poll.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "master/farm_int.h"
#include "master/http.h"
#include "master/interrupt.h"
#include "master/journal.h"
#include "proto/net.h"
#include "proto/serial.h"

void farm_log(const struct farm *f, const char *fmt, ...)
{
	/* farm faults are printed even with -q: it quiets progress, not warnings */
	va_list ap;
	va_start(ap, fmt);
	if (f->tty)
		fputs("\r\033[K", stderr);
	fputs("portray-master: ", stderr);
	vfprintf(stderr, fmt, ap);
	fputc('\n', stderr);
	va_end(ap);
}

void farm_log_limited(struct farm *f, const char *fmt, ...)
{
	double now = net_now();
	if (now - f->log_since >= FARM_LOG_PERIOD_S) {
		if (f->log_left_out)
			farm_log(f, "(%u more lines about workers dialling in left out in %.0f s)", f->log_left_out,
				 now - f->log_since);
		f->log_since = now;
		f->log_n = f->log_left_out = 0;
	}
	if (f->log_n >= FARM_LOG_BURST) {
		f->log_left_out++;
		return;
	}
	f->log_n++;
	char line[1024];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(line, sizeof line, fmt, ap);
	va_end(ap);
	farm_log(f, "%s", line);
}

static void join_check(struct farm *f);

void farm_check_alive(struct farm *f)
{
	if (!f->o->no_local)
		return;
	for (uint32_t i = 0; i < f->n_w; i++)
		if (!f->w[i].dropped)
			return;
	if (f->o->min_workers && !f->joined_enough) {
		join_check(f); /* too few joined: --min-workers' verdict (75), not 69 */
		if (f->rc)
			return;
	}
	if (f->lfd >= 0) {
		/* workers may still dial in: wait for them */
		if (!f->said_waiting)
			farm_log(f, "no worker connected: waiting for workers to dial in on %s", f->accept_at);
		f->said_waiting = true;
		return;
	}
	f->rc = EXIT_NO_WORKERS;
	ev_stop(f->loop);
}

/* ---- workers that dial in (--accept) ---- */

/*
 * A slot for a worker that dialled in: a new one, or one whose connection
 * never delivered anything. When FARM_ACCEPT_MAX are connected, the oldest
 * one that has not passed its HELLO is evicted for the newcomer (as a worker
 * does with its own unauthenticated peers), so a flood of idle connections
 * cannot keep a real worker out: it sends its HELLO as soon as it is
 * connected and is past the eviction order before many more arrive.
 */
static struct worker *accept_slot(struct farm *f)
{
	uint32_t live = 0;
	struct worker *reuse = NULL, *victim = NULL;
	for (uint32_t i = 0; i < f->n_w; i++) {
		struct worker *w = &f->w[i];
		if (!w->accepted)
			continue;
		if (w->state != W_IDLE) {
			live++;
			if (!w->spoke && (!victim || w->accepted_at < victim->accepted_at))
				victim = w;
		} else if (!reuse && w->delivered == 0 && w->tiles_done == 0) {
			reuse = w;
		}
	}
	if (live >= FARM_ACCEPT_MAX) {
		if (!victim)
			return NULL;
		if (victim->pc) {
			proto_send_error(victim->pc, PERR_LIMIT, "evicted: too many connections dialling in");
			proto_conn_flush(victim->pc);
		}
		worker_close(victim);
		victim->dropped = true;
		f->n_evicted++;
		reuse = victim;
	}
	if (reuse) {
		uint16_t index = reuse->index;
		worker_free(reuse);
		return worker_init(f, reuse, &(struct worker_addr){ "", "", "" }, index) < 0 ? NULL : reuse;
	}
	if (f->n_w == f->cap_w)
		return NULL;
	struct worker *w = &f->w[f->n_w];
	if (worker_init(f, w, &(struct worker_addr){ "", "", "" }, (uint16_t)f->n_w) < 0)
		return NULL;
	f->n_w++;
	return w;
}

static void on_accept(struct ev_loop *l, int lfd, short revents, void *arg)
{
	(void)l;
	(void)revents;
	struct farm *f = arg;
	for (int k = 0; k < 16; k++) {
		char peer[96];
		int fd = net_accept(lfd, peer, sizeof peer);
		if (fd < 0)
			return;
		struct worker *w = atomic_load(sched_stop_flag(f->s)) ? NULL : accept_slot(f);
		if (!w) {
			close(fd);
			farm_log_limited(f, "worker %s refused: %d workers that dialled in are working already", peer,
					 FARM_ACCEPT_MAX);
			continue;
		}
		snprintf(w->addr.name, sizeof w->addr.name, "%s", peer);
		const char *colon = strrchr(peer, ':');
		snprintf(w->addr.host, sizeof w->addr.host, "%.*s", colon ? (int)(colon - peer) : (int)strlen(peer), peer);
		w->name = w->addr.name;
		w->accepted_at = net_now();
		worker_accepted(w, fd); /* "dialled in" is said once its HELLO passes */
	}
}

/* Listens for workers that dial in; 0, or -1 with a message printed. */
static int start_accepting(struct farm *f)
{
	char host[NET_HOST_LEN], port[NET_PORT_LEN], err[300];
	if (net_parse_hostport(f->o->accept, host, port, err, sizeof err) < 0) {
		fprintf(stderr, "portray-master: --accept: %s\n", err);
		return -1;
	}
	f->lfd = net_listen(host, port, err, sizeof err);
	if (f->lfd < 0) {
		fprintf(stderr, "portray-master: --accept: %s\n", err);
		return -1;
	}
	int bound = net_local_port(f->lfd);
	if (f->o->port_file && net_write_number(f->o->port_file, bound) < 0) {
		fprintf(stderr, "portray-master: cannot write %s: %s\n", f->o->port_file, strerror(errno));
		return -1;
	}
	if (ev_io_set(f->loop, f->lfd, POLLIN, on_accept, f) < 0) {
		fprintf(stderr, "portray-master: out of memory\n");
		return -1;
	}
	snprintf(f->accept_at, sizeof f->accept_at, strchr(host, ':') ? "[%s]:%d" : "%s:%d", host, bound);
	if (!f->o->quiet)
		farm_log(f, "accepting workers on %s", f->accept_at);
	return 0;
}

static void stop_accepting(struct farm *f)
{
	if (f->lfd < 0)
		return;
	ev_io_del(f->loop, f->lfd);
	close(f->lfd);
	f->lfd = -1;
}

/* ---- local threads: a tile source over the scheduler ---- */

struct local {
	struct farm *f;
	const struct renderer *r;
	bool audit_only;       /* --no-local: audits, never ordinary tiles */
	atomic_uint oom;       /* tile buffers refused in a row */
};

static int local_take(void *ctx, struct tile_work *w)
{
	struct local *L = ctx;
	uint32_t id;
	bool audit;
	if (atomic_load(&L->f->local_gave_up) || !sched_local_take(L->f->s, L->audit_only, &id, &audit))
		return 0;
	*w = (struct tile_work){ L->r, sched_rect(L->f->s, id), sched_stop_flag(L->f->s), id, audit ? L : NULL, 0,
				 L->f->px };
	return 1;
}

static void local_done(void *ctx, const struct tile_work *w, uint8_t **rgb, int ok)
{
	struct local *L = ctx;
	sched_local_done(L->f->s, (uint32_t)w->id, w->ptr != NULL, *rgb, ok == 1);
	if (ok >= 0) {
		atomic_store(&L->oom, 0);
	} else if (atomic_fetch_add(&L->oom, 1) + 1 >= FARM_LOCAL_OOM_MAX) {
		/* no tile buffer, again and again: give up rather than spin (the
		 * tile went back to the queue; a worker may still take it) */
		atomic_store(&L->f->local_gave_up, 1);
		ev_wake(L->f->loop);
	}
}

/* Starts the local threads (none with --no-local and no audits). 0, or -1
 * with a message printed. */
static int local_start(struct farm *f)
{
	if (f->n_threads > 0 && !f->pool && !(f->pool = tile_pool_start(f->n_threads, f->src))) {
		fprintf(stderr, "portray-master: cannot start a local thread\n");
		return -1;
	}
	return 0;
}

/* ---- --min-workers: the workers that joined ---- */

/*
 * A worker joined once it is ready to trace: handshake passed, scene
 * transferred (or found in its cache) and built; one that delivered a tile
 * counts even if lost since. When min_workers joined, the local threads
 * start (tiles went to the joined workers meanwhile); when that can no
 * longer happen (every worker named joined or failed for good and nobody
 * may dial in, or --join-timeout passed) the loop ends with EXIT_TOO_FEW.
 */
static void join_check(struct farm *f)
{
	const struct master_opts *o = f->o;
	if (!o->min_workers || f->joined_enough || f->rc)
		return;
	uint32_t joined = 0, pending = 0;
	for (uint32_t i = 0; i < f->n_w; i++) {
		struct worker *w = &f->w[i];
		if (w->accepted && !w->spoke)
			continue;
		if (w->state == W_READY || w->tiles_done > 0)
			w->joined = true;
		if (w->joined)
			joined++;
		else if (!w->dropped)
			pending++;
	}
	f->n_joined = joined;
	if (joined >= o->min_workers) {
		f->joined_enough = true;
		if (!o->quiet)
			farm_log(f, "%u worker%s joined (--min-workers %u)%s", joined, joined == 1 ? "" : "s",
				 o->min_workers, o->no_local ? "" : ": the local threads start");
		if (local_start(f) < 0) {
			f->rc = ERRLEVEL_FATAL;
			ev_stop(f->loop);
		}
		return;
	}
	double now = net_now();
	const char *why = NULL;
	if (f->lfd < 0 && pending == 0)
		why = joined ? "the other workers named failed" : "every worker named failed";
	else if (now >= f->join_deadline)
		why = "--join-timeout passed";
	if (why) {
		farm_log(f, "--min-workers %u: only %u worker%s joined (%s); no image written", o->min_workers,
			 joined, joined == 1 ? "" : "s", why);
		f->rc = EXIT_TOO_FEW;
		ev_stop(f->loop);
		return;
	}
	ev_timer_arm(f->loop, &f->join, now + FARM_JOIN_TICK_S);
}

static void on_join(struct ev_loop *l, void *arg)
{
	(void)l;
	join_check(arg);
}

/* ---- progress and summary ---- */

/* The line's farm part: each worker's rate over its last second or so. NULL
 * for a local render. */
static const struct progress_farm *progress_farm(struct farm *f, double now, struct progress_farm *pf)
{
	if (!f->farmed)
		return NULL;
	uint32_t n = 0;
	for (uint32_t i = 0; i < f->n_w; i++) {
		struct worker *w = &f->w[i];
		double dt = now - w->rate_t0;
		if (dt >= 1.0 || w->rate_t0 == 0) {
			if (w->rate_t0 > 0)
				w->rate = (w->tiles_done - w->rate_n0) / dt;
			w->rate_t0 = now;
			w->rate_n0 = w->tiles_done;
		}
		if (w->accepted && !w->spoke)
			continue; /* dialled in, not (yet) a worker */
		f->peers[n++] = (struct progress_peer){ w->name, w->rate, w->state == W_READY, w->dropped };
	}
	struct sched_stats st;
	sched_stats(f->s, &st);
	double dt = now - f->local_t0;
	if (dt >= 1.0 || f->local_t0 == 0) {
		if (f->local_t0 > 0)
			f->local_rate = (st.local_done - f->local_n0) / dt;
		f->local_t0 = now;
		f->local_n0 = st.local_done;
	}
	*pf = (struct progress_farm){ f->local_rate, f->peers, n };
	return pf;
}

static void progress_draw(struct farm *f)
{
	double now = net_now();
	struct sched_stats st;
	struct progress_farm pf;
	const struct progress_farm *fp = progress_farm(f, now, &pf);
	sched_stats(f->s, &st);
	progress_show(&f->bar, st.done, now, fp);
}

static void on_progress(struct ev_loop *l, void *arg)
{
	struct farm *f = arg;
	progress_draw(f);
	ev_timer_arm(l, &f->progress, net_now() + FARM_PROGRESS_TICK_S);
}

static void summary(struct farm *f)
{
	struct sched_stats st;
	sched_stats(f->s, &st);
	if (f->bar.mode != PROGRESS_OFF) {
		struct progress_farm pf;
		double now = net_now();
		progress_finish(&f->bar, st.done, now, progress_farm(f, now, &pf));
	}
	if (f->o->quiet || !f->farmed)
		return; /* a local render's summary is render.c's one line */
	double el = net_now() - f->t0;
	uint64_t sent = 0, scene = 0;
	for (uint32_t i = 0; i < f->n_w; i++) {
		sent += f->w[i].bytes_out;
		scene += f->w[i].scene_bytes;
	}
	fprintf(stderr,
		"portray-master: farm: %u tiles of %u px in %.2f s; %u re-dispatched, %u duplicates (%u wasted), "
		"%u invalid results, %u audits (%u failed)\n",
		st.n, f->tg.side, el, st.redispatched, st.duplicates, st.dup_wasted, f->invalid_results, st.audits,
		st.audit_failed);
	fprintf(stderr, "portray-master:   %-24s %6u tiles %5.1f%%\n", "local", st.local_done,
		100.0 * st.local_done / st.n);
	uint32_t silent = f->n_mute;
	for (uint32_t i = 0; i < f->n_w; i++) {
		struct worker *w = &f->w[i];
		if (w->accepted && !w->spoke) { /* dialled in and said nothing valid: counted below */
			silent += w->state != W_IDLE || !w->dropped;
			continue;
		}
		fprintf(stderr,
			"portray-master:   %-24s %6u tiles %5.1f%%  %u threads  window %u  rtt %.1f ms  sent %llu B "
			"(scene %llu B, cache %s)  received %llu B%s%s\n",
			w->name, w->tiles_done, 100.0 * w->tiles_done / st.n, w->threads, w->depth, w->rtt * 1e3,
			(unsigned long long)w->bytes_out, (unsigned long long)w->scene_bytes,
			w->threads == 0 ? "-" : w->cache_hit ? "hit" : "miss", (unsigned long long)w->bytes_in,
			w->why[0] ? "  last problem: " : "", w->why);
	}
	fprintf(stderr, "portray-master: farm: bytes sent %llu (scene %llu, encoded scene %zu B)\n",
		(unsigned long long)sent, (unsigned long long)scene, f->scene_len);
	if (silent || f->n_evicted)
		fprintf(stderr,
			"portray-master: farm: %u connections dialled in without a valid HELLO, %u more evicted to make "
			"room\n",
			silent, f->n_evicted);
}

/* ---- the loop ---- */

int farm_observe(struct farm *f, const struct farm_observer *o)
{
	if (f->n_obs == FARM_OBSERVERS_MAX || sched_observe(f->s) < 0)
		return -1;
	f->obs[f->n_obs++] = *o;
	return 0;
}

/* Tells the observers which tiles changed. */
static void observe_changes(struct farm *f)
{
	uint32_t ids[256], n;
	if (f->n_obs == 0)
		return;
	while ((n = sched_changes(f->s, ids, 256)) > 0)
		for (uint32_t i = 0; i < f->n_obs; i++)
			f->obs[i].tiles(f->obs[i].arg, f, ids, n);
}

/* The change list between wakes: sched wakes the loop for a change at most
 * every SCHED_CHANGE_WAKE_S, so the observers look that often too. */
static void on_observe(struct ev_loop *l, void *arg)
{
	struct farm *f = arg;
	observe_changes(f);
	ev_timer_arm(l, &f->observe, net_now() + SCHED_CHANGE_WAKE_S);
}

/* The scheduler or an interrupt has news: the render ended, a worker was
 * caught (its tiles are back in the queue), or we are cancelled. */
static void on_wake(struct ev_loop *l, void *arg)
{
	struct farm *f = arg;
	observe_changes(f);
	if (atomic_load(f->cancel) || sched_finished(f->s) || (atomic_load(&f->local_gave_up) && !f->farmed)) {
		sched_stop(f->s);
		ev_stop(l);
		return;
	}
	for (uint32_t i = 0; i < f->n_w; i++)
		worker_check_caught(&f->w[i]);
	for (uint32_t i = 0; i < f->n_w; i++)
		worker_dispatch(&f->w[i]);
}

static void wake_loop(void *arg)
{
	struct farm *f = arg;
	ev_wake(f->loop);
}

/* Says goodbye to every connected worker, giving the bytes a moment to leave. */
static void farm_bye(struct farm *f)
{
	stop_accepting(f);
	for (uint32_t i = 0; i < f->n_w; i++)
		worker_bye(&f->w[i]);
	double until = net_now() + 1.0;
	for (;;) {
		bool pending = false;
		for (uint32_t i = 0; i < f->n_w; i++) {
			struct worker *w = &f->w[i];
			if (w->pc && proto_conn_outq(w->pc) && proto_conn_flush(w->pc) == 0)
				pending |= proto_conn_outq(w->pc) > 0;
		}
		double left = until - net_now();
		if (!pending || left <= 0)
			break;
		ev_run_once(f->loop, left < 0.01 ? left : 0.01);
	}
	for (uint32_t i = 0; i < f->n_w; i++)
		worker_close(&f->w[i]);
}

/* A 64-bit mix (splitmix64's finaliser) for a salt when no random source answers. */
static uint64_t mix64(uint64_t x)
{
	x ^= x >> 30;
	x *= 0xbf58476d1ce4e5b9ULL;
	x ^= x >> 27;
	x *= 0x94d049bb133111ebULL;
	return x ^ (x >> 31);
}

int farm_render(const struct master_opts *o, const uint8_t *scene, size_t scene_len, const uint8_t *scene_hash,
		double build_s, const struct renderer *r, uint32_t w, uint32_t h, uint8_t *image, enum render_pixel px,
		atomic_int *cancel, uint32_t *finished, struct journal *jn)
{
	struct farm f;
	memset(&f, 0, sizeof f);
	f.o = o;
	f.t0 = net_now();
	f.tty = progress_wanted(o->quiet);
	f.farmed = o->workers || o->workers_file || o->accept;
	atomic_init(&f.local_gave_up, 0);
	*finished = 0;
	f.hb_timeout = o->heartbeat_s > 0 ? o->heartbeat_s : 10.0;
	f.hb_interval = f.hb_timeout / 4;
	f.scene = scene;
	f.scene_len = scene_len;
	f.build_s = build_s;
	f.width = w;
	f.height = h;
	f.px = px;
	f.cancel = cancel;
	f.lfd = -1;
	if (f.farmed) /* the pixel probe, rendered now (a few ms), not in the first handshake */
		(void)proto_build_id();
	int rc = EXIT_USAGE;
	struct worker_addr *addrs = NULL;
	struct http *view = NULL;
	struct local L;
	char err[600];

	uint32_t named = 0;
	if ((o->workers || o->workers_file) &&
	    (workers_parse(o->workers, o->workers_file, &addrs, &named, err, sizeof err) < 0 ||
	     workers_expand(&addrs, &named, err, sizeof err) < 0)) {
		fprintf(stderr, "portray-master: %s\n", err);
		goto out;
	}
	if (o->secret_file) {
		char warn[512];
		if (proto_read_secret(o->secret_file, &f.secret, &f.secret_len, err, sizeof err, warn, sizeof warn) < 0) {
			fprintf(stderr, "portray-master: --secret-file: %s\n", err);
			goto out;
		}
		if (warn[0])
			fprintf(stderr, "portray-master: warning: --secret-file %s\n", warn);
	}
	rc = ERRLEVEL_FATAL;
	if (scene_len > LIM_SCENE_BYTES) {
		fprintf(stderr, "portray-master: the encoded scene (%zu bytes) is over the wire limit\n", scene_len);
		goto out;
	}
	memcpy(f.hash, scene_hash, sizeof f.hash);
	if (o->region) /* render.c checked it is inside the image */
		tiling_init_region(&f.tg, w, h, o->tile, o->rx0, o->ry0, o->rx1, o->ry1);
	else
		tiling_init(&f.tg, w, h, o->tile);
	/* audits: random per render, so a worker cannot tell which tiles are sampled */
	uint64_t salt = 0;
	if (o->audit > 0 && proto_random((uint8_t *)&salt, sizeof salt) < 0)
		salt = mix64((uint64_t)getpid() ^ (uint64_t)(net_now() * 1e9));
	f.cap_w = named + (o->accept ? FARM_ACCEPT_MAX * 4 : 0);
	f.loop = ev_new();
	f.s = f.loop ? sched_new(&f.tg, render_pixel_bytes(px), f.cap_w, image, o->audit, salt, wake_loop, &f) : NULL;
	f.w = calloc(f.cap_w, sizeof *f.w);
	f.peers = calloc(f.cap_w ? f.cap_w : 1, sizeof *f.peers);
	if (!f.loop || !f.s || !f.w || !f.peers) {
		fprintf(stderr, "portray-master: out of memory for %u tiles\n", f.tg.n);
		goto out;
	}
	for (; f.n_w < named; f.n_w++)
		if (worker_init(&f, &f.w[f.n_w], &addrs[f.n_w], (uint16_t)f.n_w) < 0) {
			fprintf(stderr, "portray-master: out of memory\n");
			goto out;
		}
	if (o->accept && start_accepting(&f) < 0)
		goto out;
	ev_on_wake(f.loop, on_wake, &f);
	interrupt_on_cancel(wake_loop, &f);

	/* local threads; with --no-local one that only audits (none without audits) */
	int n_threads = o->no_local ? (o->audit > 0) : o->threads > 0 ? o->threads : render_ncpus();
	L = (struct local){ .f = &f, .r = r, .audit_only = o->no_local };
	atomic_init(&L.oom, 0);
	struct tile_source src = { local_take, local_done, &L };
	f.src = &src;
	f.n_threads = n_threads;
	if (o->min_workers && !o->accept && f.n_w < o->min_workers) {
		farm_log(&f, "--min-workers %u: only %u worker%s named (addresses included); no image written",
			 o->min_workers, f.n_w, f.n_w == 1 ? "" : "s");
		rc = EXIT_TOO_FEW;
		goto out;
	}
	if (o->http && http_start(&f, n_threads, &view) < 0)
		goto out;
	/* the journal's tiles are done before anything is taken (after the other observers: they see them) */
	if (jn && journal_attach(jn, &f) < 0)
		goto out;
	if (f.n_obs) {
		ev_timer_init(&f.observe, on_observe, &f);
		ev_timer_arm(f.loop, &f.observe, net_now() + SCHED_CHANGE_WAKE_S);
	}
	/* before the workers start: one failing at once already asks join_check */
	f.join_deadline = f.t0 + o->join_timeout_s;
	ev_timer_init(&f.join, on_join, &f);
	for (uint32_t i = 0; i < f.n_w; i++)
		worker_start(&f.w[i]);
	/* with --min-workers the local threads wait for the workers (join_check) */
	if (!(o->min_workers && !o->no_local) && local_start(&f) < 0)
		goto out;
	if (o->min_workers)
		join_check(&f);
	enum progress_mode pm = progress_mode_for(o->quiet);
	if (pm == PROGRESS_LINES && o->progress_interval == 0)
		pm = PROGRESS_OFF;
	progress_init(&f.bar, f.tg.n, pm, o->progress_interval, f.t0);
	if (pm != PROGRESS_OFF) {
		ev_timer_init(&f.progress, on_progress, &f);
		ev_timer_arm(f.loop, &f.progress, net_now() + FARM_PROGRESS_TICK_S);
	}
	farm_check_alive(&f); /* every worker may have failed at once */
	if (f.rc == 0 && !atomic_load(cancel) && !sched_finished(f.s) && ev_run(f.loop) < 0)
		fprintf(stderr, "portray-master: poll: %s\n", strerror(errno));
	rc = f.rc;
	sched_stop(f.s);
	tile_pool_join(f.pool);
	f.pool = NULL;
	observe_changes(&f); /* the last tiles, and those finished while stopping */
	farm_bye(&f);
	summary(&f);
	http_finish(view); /* the viewers' last tiles, and --http-linger */
	struct sched_stats st;
	sched_stats(f.s, &st);
	*finished = st.done;
	if (rc == 0 && st.done < st.n && atomic_load(&f.local_gave_up))
		rc = ERRLEVEL_LEVEL2; /* render.c writes what there is and says why */
	else if (rc == EXIT_NO_WORKERS)
		fprintf(stderr,
			"portray-master: every worker is lost and --no-local forbids rendering here: %u of %u tiles done\n",
			st.done, st.n);
	else if (rc == 0 && st.done < st.n && !atomic_load(cancel))
		rc = ERRLEVEL_FATAL;

out:
	journal_detach(jn);
	interrupt_on_cancel(NULL, NULL);
	if (f.loop)
		stop_accepting(&f);
	if (f.pool) {
		sched_stop(f.s);
		tile_pool_join(f.pool);
	}
	http_free(view);
	for (uint32_t i = 0; f.w && i < f.n_w; i++)
		worker_free(&f.w[i]);
	free(f.w);
	free(f.peers);
	sched_free(f.s);
	ev_free(f.loop);
	free(f.secret);
	free(addrs);
	return rc;
}
