// spherechain runtime — the body of the crease rule's narrow phase (skin_contacts.cpp's file comment),
// included twice there: as CreaseSweep (baseline x86-64: SSE2, or scalar) and, on x86-64, as
// CreaseSweepAvx512 under a function-level AVX-512 target (SPHERECHAIN_SKIN_AVX512 1: the 16-lane box tests
// in one compare per bound). Run picks one per job (kernels::Best(), capped by SPHERECHAIN_ISA); both report
// the same contacts in the same order.
// NOLINT(build/header_guard): a fragment of a struct body, not a header.
  struct Counters {
    uint32_t patch_pairs = 0, box_tests = 0, tests = 0, degenerate = 0, folds = 0, contacts = 0, joint_culled = 0;
  };

  /// OverlapMask16 (file scope), in one AVX-512 compare per bound when this copy is built for it.
  static uint32_t Overlap16(const float* b, const float lo[3], const float hi[3]) {
#if SPHERECHAIN_SKIN_AVX512
    __mmask16 in = _mm512_cmp_ps_mask(_mm512_loadu_ps(b), _mm512_set1_ps(hi[0]), _CMP_LE_OQ);
    in = _mm512_mask_cmp_ps_mask(in, _mm512_loadu_ps(b + 16), _mm512_set1_ps(hi[1]), _CMP_LE_OQ);
    in = _mm512_mask_cmp_ps_mask(in, _mm512_loadu_ps(b + 32), _mm512_set1_ps(hi[2]), _CMP_LE_OQ);
    in = _mm512_mask_cmp_ps_mask(in, _mm512_loadu_ps(b + 48), _mm512_set1_ps(lo[0]), _CMP_GE_OQ);
    in = _mm512_mask_cmp_ps_mask(in, _mm512_loadu_ps(b + 64), _mm512_set1_ps(lo[1]), _CMP_GE_OQ);
    in = _mm512_mask_cmp_ps_mask(in, _mm512_loadu_ps(b + 80), _mm512_set1_ps(lo[2]), _CMP_GE_OQ);
    return static_cast<uint32_t>(in);
#else
    return OverlapMask16(b, lo, hi);
#endif
  }

  static uint32_t PatchCount(const NarrowPhaseModel& m) { return static_cast<uint32_t>(m.cl_tri_.size() / kPatch); }
  static uint32_t GroupCount(const NarrowPhaseModel& m) { return (PatchCount(m) + kGroup - 1) / kGroup; }

  static constexpr uint32_t kWindow = 64;  // pairs of patches fewer than this apart: in near_win_
  /// The near block of patches a <= b (an index into near_rows_ / near_far_), kAllNear, or kFarPair when no
  /// pair of the two is near. Pairs fewer than kWindow patches apart (the patches are in Morton order:
  /// 87 % of the pairs a MakeHuman frame looks up) from a's two window masks; the others from a's sorted
  /// row of partners further apart (near_out_: 12 a patch on average, the pairs of a patch it holds a near
  /// pair with), both a few hundred KB for MakeHuman, where a hash table's random reads missed the caches.
  static uint32_t NearBlock(const NarrowPhaseModel& m, uint32_t a, uint32_t b) {
    const uint32_t d = b - a;
    if (d < kWindow) {
      const uint64_t bit = uint64_t{1} << d, blocks = m.near_win_[2 * size_t{a} + 1];
      if (m.near_win_[2 * size_t{a}] & bit) return kAllNear;
      if (!(blocks & bit)) return kFarPair;
      return m.near_base_[a] + static_cast<uint32_t>(__builtin_popcountll(blocks & (bit - 1)));
    }
    const uint64_t key = uint64_t{b} << 32;
    for (uint32_t k = m.near_out_offsets_[a], end = m.near_out_offsets_[a + 1]; k < end; ++k) {
      const uint64_t entry = m.near_out_[k];
      if (entry >= key) return entry >> 32 == b ? static_cast<uint32_t>(entry) : kFarPair;
    }
    return kFarPair;
  }

  /// The restricted path: patches a and b hold triangles behind the two spheres of a listed pair, or both
  /// behind one listed sphere, or both hold a contact of the bind pose.
  static bool Listed(const NarrowPhaseModel& m, const NarrowPhaseWorkspace& w, uint32_t a, uint32_t b) {
    if (m.patch_bind_[a] & m.patch_bind_[b]) return true;
    const size_t words = SphereWords(m);
    const uint64_t* partners = &w.patch_partner_bits_[a * words];
    const uint64_t* spheres = &m.patch_sphere_bits_[b * words];
    uint64_t any = 0;
    for (size_t k = 0; k < words; ++k) any |= partners[k] & spheres[k];
    return any != 0;
  }
  static size_t SphereWords(const NarrowPhaseModel& m) { return (size_t{m.sphere_count_} + 63) / 64; }

  /// Patches and near bits (file comment) from the bind pose `bind` (#V×3) and the model's graph.
  static Status BuildPatches(NarrowPhaseModel& m, const float* bind) {
    const CreaseGraph& g = m.crease_graph_;
    const uint32_t T = static_cast<uint32_t>(m.tri_v_.size() / 3), N = g.node_count();
    auto valid = [&](uint32_t t) {
      const uint32_t* v = &m.tri_v_[3 * size_t{t}];
      const uint32_t w0 = m.weld_[v[0]], w1 = m.weld_[v[1]], w2 = m.weld_[v[2]];
      return w0 != w1 && w1 != w2 && w0 != w2;  // index-degenerate triangles are never tested
    };
    // Node → triangles (CSR) and each triangle's bind centroid.
    std::vector<uint32_t> nt_off(size_t{N} + 1, 0), nt_tri, order;
    std::vector<float> centroid(3 * size_t{T});
    float lo[3] = {kInfinity, kInfinity, kInfinity}, hi[3] = {-kInfinity, -kInfinity, -kInfinity};
    for (uint32_t t = 0; t < T; ++t) {
      if (!valid(t)) continue;
      order.push_back(t);
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = m.tri_v_[3 * size_t{t} + k];
        ++nt_off[g.node(v) + 1];
        for (int a = 0; a < 3; ++a) centroid[3 * size_t{t} + a] += bind[3 * size_t{v} + a] / 3.0f;
      }
      for (int a = 0; a < 3; ++a)
        lo[a] = std::min(lo[a], centroid[3 * size_t{t} + a]), hi[a] = std::max(hi[a], centroid[3 * size_t{t} + a]);
    }
    for (uint32_t n = 0; n < N; ++n) nt_off[n + 1] += nt_off[n];
    nt_tri.resize(nt_off[N]);
    {
      std::vector<uint32_t> fill(nt_off.begin(), nt_off.end() - 1);
      for (uint32_t t : order)
        for (int k = 0; k < 3; ++k) nt_tri[fill[g.node(m.tri_v_[3 * size_t{t} + k])]++] = t;
    }
    // Seeds in Morton order of the centroids (ties by index: deterministic).
    std::vector<uint64_t> seeds(order.size());
    for (size_t i = 0; i < order.size(); ++i) {
      uint32_t q[3];
      for (int a = 0; a < 3; ++a) {
        const float span = hi[a] - lo[a];
        q[a] = span > 0.0f ? static_cast<uint32_t>(std::min(1023.0f, (centroid[3 * size_t{order[i]} + a] - lo[a]) / span * 1024.0f)) : 0;
      }
      seeds[i] = uint64_t{Morton(q[0], q[1], q[2])} << 32 | order[i];
    }
    std::sort(seeds.begin(), seeds.end());
    // Grow each patch from its seed: the unassigned triangles sharing a corner with it, nearest the seed first.
    std::vector<uint32_t> patch_of(T, kNone), seen(T, kNone), frontier;
    m.cl_tri_.clear();
    auto dist2 = [&](uint32_t a, uint32_t b) {
      float d = 0;
      for (int k = 0; k < 3; ++k) d += (centroid[3 * size_t{a} + k] - centroid[3 * size_t{b} + k]) * (centroid[3 * size_t{a} + k] - centroid[3 * size_t{b} + k]);
      return d;
    };
    // The growth's budget (NarrowPhaseModel::kGrowPerTriangle): each pick scans the patch's frontier and its
    // corners' triangles, a few dozen on a surface; around a welded vertex that is a corner of thousands of
    // triangles (a fan) every patch there scans them all, quadratic in the triangles.
    const uint64_t grow_budget = uint64_t{NarrowPhaseModel::kGrowPerTriangle} * T + NarrowPhaseModel::kSweepSlack;
    uint64_t grow_work = 0;
    for (uint64_t key : seeds) {
      const uint32_t seed = static_cast<uint32_t>(key);
      if (patch_of[seed] != kNone) continue;
      const uint32_t p = PatchCount(m);
      m.cl_tri_.resize(m.cl_tri_.size() + kPatch, kNone);
      frontier.assign(1, seed);
      seen[seed] = p;
      for (uint32_t n_in = 0; n_in < kPatch && !frontier.empty();) {
        size_t best = 0;
        for (size_t i = 1; i < frontier.size(); ++i)
          if (dist2(frontier[i], seed) < dist2(frontier[best], seed) ||
              (dist2(frontier[i], seed) == dist2(frontier[best], seed) && frontier[i] < frontier[best]))
            best = i;
        const uint32_t t = frontier[best];
        grow_work += frontier.size();
        frontier[best] = frontier.back();
        frontier.pop_back();
        patch_of[t] = p;
        m.cl_tri_[kPatch * size_t{p} + n_in++] = t;
        for (int k = 0; k < 3; ++k) {
          const uint32_t n = g.node(m.tri_v_[3 * size_t{t} + k]);
          grow_work += nt_off[n + 1] - nt_off[n];
          if (grow_work > grow_budget) return Status::kErrorCreaseTooWide;
          for (uint32_t i = nt_off[n]; i < nt_off[n + 1]; ++i) {
            const uint32_t u = nt_tri[i];
            if (patch_of[u] == kNone && seen[u] != p) seen[u] = p, frontier.push_back(u);
          }
        }
      }
    }
    const uint32_t C = PatchCount(m);
    std::vector<uint8_t> slot_of(T, 0);
    for (size_t k = 0; k < m.cl_tri_.size(); ++k)
      if (m.cl_tri_[k] != kNone) slot_of[m.cl_tri_[k]] = static_cast<uint8_t>(k % kPatch);
    // Each patch's distinct vertices, its triangles' corners among them, its triangle count (the slots are
    // filled in order: padding last) and the mask of its slots in use.
    m.cl_vert_offsets_.assign(1, 0);
    m.cl_vert_.clear();
    m.cl_local_.assign(3 * kPatch * size_t{C}, 0);
    m.cl_count_.assign(C, 0);
    m.cl_valid_.assign(C, 0);
    std::vector<uint32_t> verts;
    for (uint32_t p = 0; p < C; ++p) {
      verts.clear();
      uint32_t n = 0;
      for (uint32_t i = 0; i < kPatch; ++i) {
        const uint32_t t = m.cl_tri_[kPatch * size_t{p} + i];
        if (t == kNone) break;
        verts.insert(verts.end(), &m.tri_v_[3 * size_t{t}], &m.tri_v_[3 * size_t{t}] + 3);
        ++n;
      }
      std::sort(verts.begin(), verts.end());
      verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
      for (uint32_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
          const uint32_t v = m.tri_v_[3 * size_t{m.cl_tri_[kPatch * size_t{p} + i]} + k];
          m.cl_local_[3 * kPatch * size_t{p} + 3 * i + k] =
              static_cast<uint8_t>(std::lower_bound(verts.begin(), verts.end(), v) - verts.begin());
        }
      m.cl_count_[p] = static_cast<uint8_t>(n);
      m.cl_valid_[p] = static_cast<uint16_t>((1u << n) - 1);
      m.cl_vert_.insert(m.cl_vert_.end(), verts.begin(), verts.end());
      m.cl_vert_offsets_.push_back(static_cast<uint32_t>(m.cl_vert_.size()));
    }
    // Near bits. A triangle's near nodes (CreaseScratch::Reach) are the union of its corners' (the bounded
    // Dijkstra from three sources settles each node at its nearest corner; the ring is the corners' edge
    // neighbours), so per patch p each distinct corner node is searched once, the triangles of patches
    // q >= p at its near nodes gathered into 16-bit masks per q, and those masks OR-ed into the rows of
    // p's triangles that have that corner.
    CreaseScratch scratch;
    if (Status s = scratch.Init(g); s != Status::kOk) return s;
    // A node is a corner in two or three patches, and its search and the gathering of the triangles near it
    // are most of Init's time: each node's result is kept from its first patch to its last (last_patch), then
    // dropped, so every node is searched once and only a band of nodes (the patches are in Morton order) is
    // held at a time. Same patches, same masks, same order as a search per patch: the same model.
    std::vector<uint32_t> last_patch(N, 0);
    for (uint32_t p = 0; p < C; ++p)
      for (uint32_t k = m.cl_vert_offsets_[p]; k < m.cl_vert_offsets_[p + 1]; ++k) last_patch[g.node(m.cl_vert_[k])] = p;
    // Kept per node: the patches q its near nodes' triangles lie in, each with the 16-bit mask of those
    // triangles' slots (q << 16 | mask), in the order first met.
    std::vector<std::vector<uint64_t>> kept_near(N);
    std::vector<uint64_t> fresh;
    std::vector<uint32_t> fresh_of(C, kNone);
    std::vector<uint32_t> entry_of(C, kNone), touched;
    std::vector<uint16_t> rows;
    std::vector<uint64_t> node_entries;  // this corner node's patches q >= p: (entry << 16 | mask)
    std::vector<uint64_t> corners;  // per patch: (node << 32 | vertex << 4 | slot) of each triangle's corners
    // The searches' budget (NarrowPhaseModel::kReachPerNode): a bind pose collapsed onto a few points reaches
    // most of its surface from every node, a search and a near row per node quadratic in them; a mesh far
    // denser than its crease comes near that.
    const uint32_t reach_budget = SweepLimit(NarrowPhaseModel::kReachPerNode, N);
    // ... and the triangles at the nodes reached, gathered into the masks: a few per node on a surface, but every
    // triangle of a fan's centre each time a search reaches it.
    const uint64_t gather_budget = uint64_t{NarrowPhaseModel::kGatherPerNode} * N + NarrowPhaseModel::kSweepSlack;
    uint64_t reached = 0, gathered = 0;
    std::vector<uint64_t> pairs;  // (p << 32 | q), p <= q, for every pair of patches with a near pair
    std::vector<uint32_t> block;  // per pair in `pairs`: its rows' block in near_rows_, or kAllNear
    m.near_rows_.clear();
    m.near_far_.clear();
    auto valid_mask = [&](uint32_t p) {
      uint32_t mask = 0;
      for (uint32_t i = 0; i < kPatch; ++i) mask |= uint32_t{m.cl_tri_[kPatch * size_t{p} + i] != kNone} << i;
      return mask;
    };
    for (uint32_t p = 0; p < C; ++p) {
      touched.clear();
      rows.clear();
      corners.clear();
      for (uint32_t i = 0; i < kPatch; ++i) {
        const uint32_t t = m.cl_tri_[kPatch * size_t{p} + i];
        if (t == kNone) break;
        for (int k = 0; k < 3; ++k) {
          const uint32_t v = m.tri_v_[3 * size_t{t} + k];
          corners.push_back(uint64_t{g.node(v)} << 32 | uint64_t{v} << 4 | i);
        }
      }
      std::sort(corners.begin(), corners.end());
      for (size_t b = 0; b < corners.size();) {
        size_t e = b + 1;
        while (e < corners.size() && corners[e] >> 32 == corners[b] >> 32) ++e;
        const uint32_t v = static_cast<uint32_t>(corners[b]) >> 4, node = static_cast<uint32_t>(corners[b] >> 32);
        std::vector<uint64_t>& kept = kept_near[node];
        const std::vector<uint64_t>* near = &kept;
        if (kept.empty()) {  // a node is near its own triangles: empty means not searched yet
          const uint32_t source[3] = {v, v, v};
          fresh.clear();
          const BlockVector<uint32_t>& reach = scratch.Reach(g, source, g.crease());
          if ((reached += reach.size()) > reach_budget) return Status::kErrorCreaseTooWide;
          for (uint32_t n : reach) {
            if ((gathered += nt_off[n + 1] - nt_off[n]) > gather_budget) return Status::kErrorCreaseTooWide;
            for (uint32_t k = nt_off[n]; k < nt_off[n + 1]; ++k) {
              const uint32_t u = nt_tri[k], q = patch_of[u];
              if (fresh_of[q] == kNone) fresh_of[q] = static_cast<uint32_t>(fresh.size()), fresh.push_back(uint64_t{q} << 16);
              fresh[fresh_of[q]] |= uint64_t{1} << slot_of[u];
            }
          }
          for (uint64_t f : fresh) fresh_of[f >> 16] = kNone;
          near = &fresh;
          if (last_patch[node] != p) kept = fresh;
        }
        node_entries.clear();
        for (uint64_t f : *near) {
          const uint32_t q = static_cast<uint32_t>(f >> 16);
          if (q < p) continue;
          if (entry_of[q] == kNone) {
            entry_of[q] = static_cast<uint32_t>(touched.size());
            touched.push_back(q);
            rows.resize(rows.size() + kPatch, 0);
          }
          node_entries.push_back(uint64_t{entry_of[q]} << 16 | (f & 0xffffu));
        }
        for (size_t c = b; c < e; ++c) {
          const uint32_t i = static_cast<uint32_t>(corners[c]) & 15u;
          for (uint64_t en : node_entries) rows[kPatch * size_t(en >> 16) + i] |= static_cast<uint16_t>(en);
        }
        if (last_patch[node] == p) std::vector<uint64_t>().swap(kept);
        b = e;
      }
      const uint32_t mask_p = valid_mask(p);
      for (uint32_t q : touched) {
        uint16_t* r = &rows[kPatch * size_t{entry_of[q]}];
        const uint32_t mask_q = valid_mask(q);
        bool all = true;
        for (uint32_t i = 0; i < kPatch; ++i) {
          r[i] |= static_cast<uint16_t>(~mask_q);  // padding slots: as if near (never tested)
          if ((mask_p >> i & 1) && r[i] != 0xffffu) all = false;
        }
        uint32_t b = kAllNear;
        if (!all) {
          b = static_cast<uint32_t>(m.near_rows_.size() / kPatch);
          m.near_rows_.insert(m.near_rows_.end(), r, r + kPatch);
          // The rows (p's slots) with a partner not near, and the columns (q's) with one: the rest of
          // either patch is never looked at for this pair. Of one patch, pairs j > i only.
          uint32_t far_rows = 0, far_cols = 0;
          for (uint32_t i = 0; i < kPatch; ++i) {
            if (!(mask_p >> i & 1)) continue;
            uint32_t free = ~uint32_t{r[i]} & 0xffffu;
            if (q == p) free &= ~((2u << i) - 1);
            if (free) far_rows |= 1u << i, far_cols |= free;
          }
          m.near_far_.push_back(far_rows | far_cols << 16);
        }
        pairs.push_back(uint64_t{p} << 32 | q), block.push_back(b);
        entry_of[q] = kNone;
      }
    }
    // The blocks renumbered in the order of their pairs (p, then q): a patch's blocks are consecutive from
    // near_base_[p], those fewer than kWindow apart first, so NearBlock counts them in the window masks.
    std::vector<uint32_t> by(pairs.size());
    for (uint32_t i = 0; i < by.size(); ++i) by[i] = i;
    std::sort(by.begin(), by.end(), [&](uint32_t i, uint32_t j) { return pairs[i] < pairs[j]; });
    const std::vector<uint16_t> rows_built(m.near_rows_.begin(), m.near_rows_.end());
    const std::vector<uint32_t> far_built(m.near_far_.begin(), m.near_far_.end());
    m.near_rows_.clear();
    m.near_far_.clear();
    m.near_win_.assign(2 * size_t{C}, 0);
    m.near_base_.assign(C, 0);
    m.near_out_offsets_.assign(size_t{C} + 1, 0);
    m.near_out_.clear();
    uint32_t row = kNone;
    for (uint32_t i : by) {
      const uint32_t p = static_cast<uint32_t>(pairs[i] >> 32), q = static_cast<uint32_t>(pairs[i]);
      if (p != row) row = p, m.near_base_[p] = static_cast<uint32_t>(m.near_far_.size());
      m.near_out_offsets_[p + 1] += q - p >= kWindow;
      uint32_t b = block[i];
      if (b != kAllNear) {
        const uint32_t renumbered = static_cast<uint32_t>(m.near_far_.size());
        m.near_rows_.insert(m.near_rows_.end(), &rows_built[kPatch * size_t{b}], &rows_built[kPatch * size_t{b}] + kPatch);
        m.near_far_.push_back(far_built[b]);
        b = renumbered;
      }
      if (q - p < kWindow)
        m.near_win_[2 * size_t{p} + (b == kAllNear ? 0 : 1)] |= uint64_t{1} << (q - p);
      else
        m.near_out_.push_back(uint64_t{q} << 32 | b);  // in pair order: each row sorted by q
    }
    for (uint32_t p = 0; p < C; ++p) m.near_out_offsets_[p + 1] += m.near_out_offsets_[p];
    // Per pair of groups g <= h fewer than kGroupWindow apart, bit i + 4j set when the sweep skips patches
    // 4g + i and 4h + j whole: all near, padding, or (g == h) i > j, each pair of one group once.
    const uint32_t G = GroupCount(m);
    m.group_near_.assign(kGroupWindow * size_t{G}, 0);
    for (uint32_t g = 0; g < G; ++g)
      for (uint32_t h = g; h < G && h - g < kGroupWindow; ++h) {
        uint32_t skip = 0;
        for (uint32_t j = 0; j < kGroup; ++j)
          for (uint32_t i = 0; i < kGroup; ++i) {
            const uint32_t a = kGroup * g + i, b = kGroup * h + j;
            const bool whole = a >= C || b >= C || (g == h && i > j) || NearBlock(m, a, b) == kAllNear;
            skip |= uint32_t{whole} << (i + kGroup * j);
          }
        m.group_near_[kGroupWindow * size_t{g} + (h - g)] = static_cast<uint16_t>(skip);
      }
    return Status::kOk;
  }

  /// The joint-matrix cull's model (narrow_phase.h NarrowPhaseModel, "The joint-matrix cull"), from the
  /// asset's skin rows (Asset.skin_*; none: no cull) and the bind pose. Per block the gap is the least
  /// distance between the bind boxes of its pairs not near.
  static void BuildJointCull(NarrowPhaseModel& m, const schema::Asset& a, const float* bind) {
    const auto* counts = a.skin_counts();
    const auto* joints = a.skin_joints();
    const auto* weights = a.skin_weights();
    if (!counts || !joints || !weights || a.joint_count() == 0) return;
    const uint32_t C = PatchCount(m), V = counts->size();
    std::vector<uint32_t> first(size_t{V} + 1, 0);
    for (uint32_t v = 0; v < V; ++v) first[v + 1] = first[v] + counts->Get(v);
    std::vector<uint64_t> pair_keys;  // j << 16 | r, found in order; index = position
    std::vector<std::pair<uint32_t, uint32_t>> sorted;  // (key, index)
    std::vector<double> anchor_sum;   // per pair: Σ of centres, count
    std::vector<uint32_t> anchor_n;
    auto pair_index = [&](uint32_t j, uint32_t r, const double c[3]) {
      const uint32_t key = j << 16 | r;
      auto it = std::lower_bound(sorted.begin(), sorted.end(), std::make_pair(key, 0u));
      uint32_t k;
      if (it != sorted.end() && it->first == key) {
        k = it->second;
      } else {
        k = static_cast<uint32_t>(pair_keys.size());
        pair_keys.push_back(key), anchor_sum.resize(anchor_sum.size() + 3, 0.0), anchor_n.push_back(0);
        sorted.insert(it, {key, k});
      }
      for (int i = 0; i < 3; ++i) anchor_sum[3 * size_t{k} + i] += c[i];
      ++anchor_n[k];
      return k;
    };
    std::vector<double> centre(3 * size_t{C}), radius(C);
    std::vector<uint32_t> ref(C, kNone), entry_pair, entry_patch;
    std::vector<float> entry_w, slack(C, 1.0f);
    std::vector<uint32_t> offsets(1, 0);
    std::vector<std::array<uint32_t, 3>> influence;  // joint, Σ weight, largest weight (rounded, /255)
    for (uint32_t p = 0; p < C; ++p) {
      influence.clear();
      double lo[3] = {kInfinity, kInfinity, kInfinity}, hi[3] = {-kInfinity, -kInfinity, -kInfinity};
      // Unskinned, for the bound: a vertex of no joint, or whose weights do not sum to 255 (LoadAsset allows
      // that within rounding, for assets another tool wrote): skinned with its weights as stored, such a
      // vertex strays from its joints' rigid motions by (Σ/255 − 1) of its skinned position, which no bound
      // of the matrices alone holds. Its patch is never culled.
      bool unskinned = false;
      for (uint32_t i = m.cl_vert_offsets_[p]; i < m.cl_vert_offsets_[p + 1]; ++i) {
        const uint32_t v = m.cl_vert_[i];
        uint32_t sum = 0;
        for (uint32_t e = first[v]; e < first[v + 1]; ++e) sum += weights->Get(e);
        unskinned |= counts->Get(v) == 0 || sum != 255;
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], double{bind[3 * size_t{v} + k]}), hi[k] = std::max(hi[k], double{bind[3 * size_t{v} + k]});
        for (uint32_t e = first[v]; e < first[v + 1]; ++e) {
          const uint32_t j = joints->Get(e);
          // A joint listed twice in one row (an asset the baker did not write) weighs the sum of its entries,
          // as in linear blend skinning, and each entry adds its own unit of rounding: counted at its first.
          bool listed = false;
          for (uint32_t d = first[v]; d < e && !listed; ++d) listed = joints->Get(d) == j;
          if (listed) continue;
          uint32_t q = 0, entries = 0;
          for (uint32_t d = e; d < first[v + 1]; ++d)
            if (joints->Get(d) == j) q += weights->Get(d), ++entries;
          size_t f = 0;
          while (f < influence.size() && influence[f][0] != j) ++f;
          if (f == influence.size()) influence.push_back({j, 0, 0});
          influence[f][1] += q, influence[f][2] = std::max(influence[f][2], q + entries - 1);
        }
      }
      double* c = &centre[3 * size_t{p}];
      for (int k = 0; k < 3; ++k) c[k] = 0.5 * (lo[k] + hi[k]);
      double r2 = 0.0;
      for (uint32_t i = m.cl_vert_offsets_[p]; i < m.cl_vert_offsets_[p + 1]; ++i) {
        double d2 = 0.0;
        for (int k = 0; k < 3; ++k) d2 += (bind[3 * size_t{m.cl_vert_[i]} + k] - c[k]) * (bind[3 * size_t{m.cl_vert_[i]} + k] - c[k]);
        r2 = std::max(r2, d2);
      }
      radius[p] = std::sqrt(r2) * (1.0 + 1e-6);
      if (!unskinned && !influence.empty()) {
        size_t best = 0;
        for (size_t f = 1; f < influence.size(); ++f)
          if (influence[f][1] > influence[best][1] || (influence[f][1] == influence[best][1] && influence[f][0] < influence[best][0]))
            best = f;
        ref[p] = influence[best][0];
        // The reference joint's least weight on the patch (0 where a vertex lacks it), rounded down (a
        // joint listed k times: the sum of its entries less k − 1 units, the formula below taking one more).
        uint32_t least = 255;
        for (uint32_t i = m.cl_vert_offsets_[p]; i < m.cl_vert_offsets_[p + 1]; ++i) {
          const uint32_t v = m.cl_vert_[i];
          uint32_t q = 0, entries = 0;
          for (uint32_t e = first[v]; e < first[v + 1]; ++e)
            if (joints->Get(e) == ref[p]) q += weights->Get(e), ++entries;
          least = std::min(least, entries == 0 ? 0u : q + 1 > entries ? q + 1 - entries : 0u);
        }
        slack[p] = static_cast<float>(std::min(1.0, 1.0 - (least > 0 ? least - 1 : 0) / 255.0 + 1e-6));
        for (const auto& f : influence) {
          if (f[0] == ref[p]) continue;
          entry_pair.push_back(pair_index(f[0], ref[p], c));
          entry_patch.push_back(p);
          entry_w.push_back(static_cast<float>(std::min(1.0, (f[2] + 1) / 255.0 + 1e-6)));
        }
      }
      offsets.push_back(static_cast<uint32_t>(entry_pair.size()));
    }
    // Per block: its gap, and the pair of references when they differ.
    const size_t B = m.near_far_.size();
    std::vector<float> gap(B, 0.0f);
    std::vector<uint32_t> cross(B, kNone), cross_patch(B, kNone);
    auto block_gap = [&](uint32_t p, uint32_t q, uint32_t block) {
      const uint16_t* rows = &m.near_rows_[kPatch * size_t{block}];
      float box[2][kPatch][6];
      for (int side = 0; side < 2; ++side)
        for (uint32_t i = 0; i < kPatch; ++i) {
          const uint32_t t = m.cl_tri_[kPatch * size_t{side ? q : p} + i];
          if (t == kNone) continue;
          for (int k = 0; k < 3; ++k) box[side][i][k] = kInfinity, box[side][i][3 + k] = -kInfinity;
          for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k) {
              const float x = bind[3 * size_t{m.tri_v_[3 * size_t{t} + j]} + k];
              box[side][i][k] = std::min(box[side][i][k], x), box[side][i][3 + k] = std::max(box[side][i][3 + k], x);
            }
        }
      // The least distance of their bind boxes: a lower bound on their triangles' (exact triangle distances
      // culled 2 % more of MakeHuman's pairs and made Init 40 % slower).
      double best = std::numeric_limits<double>::infinity();
      for (uint32_t i = 0; i < kPatch; ++i) {
        if (m.cl_tri_[kPatch * size_t{p} + i] == kNone) continue;
        for (uint32_t j = 0; j < kPatch; ++j) {
          if ((rows[i] >> j & 1) || (p == q && j <= i)) continue;  // near or padding, or one patch's pair twice
          double d2 = 0.0;
          for (int k = 0; k < 3; ++k) {
            const double d = std::max({0.0, double{box[1][j][k]} - box[0][i][3 + k], double{box[0][i][k]} - box[1][j][3 + k]});
            d2 += d * d;
          }
          best = std::min(best, d2);
        }
      }
      best = std::sqrt(best);
      float g = static_cast<float>(best);
      if (double{g} > best) g = std::nextafter(g, 0.0f);
      gap[block] = g;
      if (ref[p] != kNone && ref[q] != kNone && ref[p] != ref[q])
        cross[block] = pair_index(ref[q], ref[p], &centre[3 * size_t{q}]), cross_patch[block] = q;
    };
    for (uint32_t p = 0; p < C; ++p) {
      for (uint64_t bits = m.near_win_[2 * size_t{p} + 1]; bits; bits &= bits - 1) {
        const uint32_t d = static_cast<uint32_t>(__builtin_ctzll(bits));
        block_gap(p, p + d, NearBlock(m, p, p + d));
      }
      for (uint32_t k = m.near_out_offsets_[p]; k < m.near_out_offsets_[p + 1]; ++k)
        if (static_cast<uint32_t>(m.near_out_[k]) != kAllNear)
          block_gap(p, static_cast<uint32_t>(m.near_out_[k] >> 32), static_cast<uint32_t>(m.near_out_[k]));
    }
    // Anchors, then each entry's and cross pair's reach from its anchor.
    const size_t K = pair_keys.size();
    m.cull_pairs_.assign(K, 0);
    m.cull_anchor_.assign(3 * K, 0.0f);
    for (size_t k = 0; k < K; ++k) {
      m.cull_pairs_[k] = static_cast<uint32_t>(pair_keys[k]);
      for (int i = 0; i < 3; ++i) m.cull_anchor_[3 * k + i] = static_cast<float>(anchor_sum[3 * k + i] / anchor_n[k]);
    }
    auto reach = [&](uint32_t k, uint32_t p) {
      double d2 = 0.0;
      for (int i = 0; i < 3; ++i) d2 += (centre[3 * size_t{p} + i] - m.cull_anchor_[3 * size_t{k} + i]) * (centre[3 * size_t{p} + i] - m.cull_anchor_[3 * size_t{k} + i]);
      return static_cast<float>((std::sqrt(d2) + radius[p]) * (1.0 + 1e-6));
    };
    m.cl_ref_.assign(ref.begin(), ref.end());
    m.cl_slack_.assign(slack.begin(), slack.end());
    m.cl_cull_offsets_.assign(offsets.begin(), offsets.end());
    m.cl_cull_pair_.assign(entry_pair.begin(), entry_pair.end());
    m.cl_cull_w_.assign(entry_w.begin(), entry_w.end());
    m.cl_cull_reach_.assign(entry_pair.size(), 0.0f);
    for (size_t e = 0; e < entry_pair.size(); ++e) m.cl_cull_reach_[e] = reach(entry_pair[e], entry_patch[e]);
    m.near_gap_.assign(gap.begin(), gap.end());
    m.near_cross_.assign(cross.begin(), cross.end());
    m.near_cross_reach_.assign(B, 0.0f);
    for (size_t b = 0; b < B; ++b)
      if (cross[b] != kNone) m.near_cross_reach_[b] = reach(cross[b], cross_patch[b]);
    m.cull_joint_count_ = a.joint_count();
    float extent = 0.0f;
    for (size_t i = 0; i < size_t{3} * V; ++i) extent = std::max(extent, std::fabs(bind[i]));
    m.cull_bind_extent_ = extent;
  }

  /// Triangle t prepared for exact tests this frame (PrepareTriangle): its slot in the frame's pool of
  /// prepared triangles (tri_prepared_, filled in the order the tests meet them: the used part small and
  /// hot), or kNone when it is degenerate (in no contact).
  static uint32_t Prepared(const NarrowPhaseModel& m, NarrowPhaseWorkspace& w, const char* base, size_t stride,
                           uint32_t t, Counters* c) {
    uint64_t& state = w.tri_frame_[t];
    if (state >> 32 != w.frame_) {
      const uint32_t* v = &m.tri_v_[3 * size_t{t}];
      const float* p[3];
      for (int j = 0; j < 3; ++j) p[j] = reinterpret_cast<const float*>(base + stride * v[j]);
      const uint32_t slot = w.prepared_used_;
      const bool ok = PrepareTriangle(p[0], p[1], p[2], &w.tri_prepared_[slot]);
      w.prepared_used_ += ok;
      state = uint64_t{w.frame_} << 32 | (ok ? slot : kNone);
      c->degenerate += !ok;
    }
    return static_cast<uint32_t>(state);
  }

#if SPHERECHAIN_SKIN_AVX512
  /// Patch p's 16 triangles prepared by lane for the float filter this frame (PrepareFilter16: a slot of the
  /// frame's pool, filled in the order the pairs meet the patches), and in `*certified` its certified lanes.
  static const float* Filter(const NarrowPhaseModel& m, NarrowPhaseWorkspace& w, const char* base, size_t stride,
                             uint32_t p, uint32_t* certified) {
    uint64_t& state = w.patch_filter_[p];
    if (state >> 32 != w.frame_) {
      const uint32_t slot = w.filters_used_++;
      float* f = &w.filter_pool_[kFilterFloats * size_t{slot}];
      const uint32_t first = m.cl_vert_offsets_[p], n = m.cl_count_[p];
      const uint8_t* corner = &m.cl_local_[3 * kPatch * size_t{p}];
      for (uint32_t t = 0; t < kPatch; ++t)
        for (int j = 0; j < 3; ++j) {
          const float* q = reinterpret_cast<const float*>(base + stride * m.cl_vert_[first + corner[3 * t + j]]);
          for (int k = 0; k < 3; ++k) f[kPatch * (3 * j + k) + t] = t < n ? q[k] : 0.0f;
        }
      w.filter_mask_[slot] = static_cast<uint16_t>(PrepareFilter16(f, (1u << n) - 1));
      state = uint64_t{w.frame_} << 32 | slot;
    }
    const uint32_t slot = static_cast<uint32_t>(state);
    *certified = w.filter_mask_[slot];
    return &w.filter_pool_[kFilterFloats * size_t{slot}];
  }
  /// Lane `i` of a Filter block as the PreparedTriangle PrepareTriangle writes (x, y, z with G, A, M; the
  /// plane): one gather.
  static void LaneToPrepared(const float* f, uint32_t i, PreparedTriangle* out) {
    const __m512i rows = _mm512_setr_epi32(0, 48, 96, 208, 16, 64, 112, 224, 32, 80, 128, 240, 144, 160, 176, 192);
    _mm512_store_ps(out, _mm512_i32gather_ps(_mm512_add_epi32(rows, _mm512_set1_epi32(static_cast<int>(i))), f, 4));
  }
#endif

  /// Pass 1 of a frame: each patch's distinct vertices read once (cl_vert_), its box (patch_box_: per group
  /// of 4 patches 6 rows of 4) and its 16 triangle boxes (patch_tri_box_: 6 rows of 16, inverted padding)
  /// from them (cl_local_), each group's box (group_box_: 6 rows of #G), and the box of them all (lo, hi).
  /// False when a vertex is NaN or a box not finite (nothing reported).
  /// kRestricted: a patch p with active[p] != stamp is not read: its box inverted (it meets nothing), no
  /// triangle boxes; `lo`, `hi` bound the patches read (at least one). Else every patch (active unread).
  template <bool kRestricted>
  static bool Boxes(const NarrowPhaseModel& m, NarrowPhaseWorkspace& w, const char* base, size_t stride, float lo[3],
                    float hi[3], bool tri_boxes, const uint32_t* active, uint32_t stamp) {
    const uint32_t C = PatchCount(m), G = GroupCount(m);
    float* box = w.patch_box_.data();
    float* group = w.group_box_.data();
    for (int k = 0; k < 3; ++k) lo[k] = kInfinity, hi[k] = -kInfinity;
#if SPHERECHAIN_SKIN_SSE2
    alignas(16) float local[4 * 3 * kPatch];
    constexpr uint32_t kAhead = 8;
    __m128 all_lo = _mm_set1_ps(kInfinity), all_hi = _mm_set1_ps(-kInfinity), nan = _mm_setzero_ps();
    __m128 group_lo = all_lo, group_hi = all_hi;
    for (uint32_t p = 0; p < C; ++p) {
      const uint32_t* vert = &m.cl_vert_[m.cl_vert_offsets_[p]];
      const uint32_t nv = m.cl_vert_offsets_[p + 1] - m.cl_vert_offsets_[p];
      const uint8_t* corner = &m.cl_local_[3 * kPatch * size_t{p}];
      float* tb = &w.patch_tri_box_[6 * kPatch * size_t{p}];
      const bool skip = kRestricted && active[p] != stamp;
      if (p + kAhead < C && (!kRestricted || active[p + kAhead] == stamp))  // the positions are the caller's: fetched
        for (uint32_t k = m.cl_vert_offsets_[p + kAhead]; k < m.cl_vert_offsets_[p + kAhead + 1]; ++k)  // ahead
          _mm_prefetch(base + stride * m.cl_vert_[k], _MM_HINT_T0);
      __m128 vl = _mm_set1_ps(kInfinity), vh = _mm_set1_ps(-kInfinity);
      for (uint32_t i = 0; i < (skip ? 0 : nv); ++i) {
        const float* q = reinterpret_cast<const float*>(base + stride * vert[i]);
        // x, y, z, 0 without reading past the vertex (the positions are only 4-byte aligned)
        const __m128 v = _mm_movelh_ps(_mm_unpacklo_ps(_mm_load_ss(q), _mm_load_ss(q + 1)), _mm_load_ss(q + 2));
        _mm_store_ps(local + 4 * i, v);
        vl = _mm_min_ps(vl, v), vh = _mm_max_ps(vh, v), nan = _mm_or_ps(nan, _mm_cmpunord_ps(v, v));
      }
      all_lo = _mm_min_ps(all_lo, vl), all_hi = _mm_max_ps(all_hi, vh);  // every vertex read: checked below
      // A patch collapsed onto a point or a line (no extent on two axes: a part of the mesh scaled to zero to
      // hide it) has no triangle with an area, so no contact: its box is left empty and out of its group's.
      if (__builtin_popcount(static_cast<unsigned>(_mm_movemask_ps(_mm_cmpeq_ps(vl, vh))) & 7u) >= 2)
        vl = _mm_set1_ps(kInfinity), vh = _mm_set1_ps(-kInfinity);
      alignas(16) float tl[4], th[4];
      _mm_store_ps(tl, vl), _mm_store_ps(th, vh);
      float* pb = box + 6 * kGroup * size_t{p / kGroup} + p % kGroup;
      for (int k = 0; k < 3; ++k) pb[kGroup * k] = tl[k], pb[kGroup * (3 + k)] = th[k];
      group_lo = _mm_min_ps(group_lo, vl), group_hi = _mm_max_ps(group_hi, vh);
      if (p % kGroup == kGroup - 1 || p + 1 == C) {
        _mm_store_ps(tl, group_lo), _mm_store_ps(th, group_hi);
        for (int k = 0; k < 3; ++k) group[k * size_t{G} + p / kGroup] = tl[k], group[(3 + k) * size_t{G} + p / kGroup] = th[k];
        group_lo = _mm_set1_ps(kInfinity), group_hi = _mm_set1_ps(-kInfinity);
      }
      if (!tri_boxes || skip) continue;  // the joint-matrix cull: built when a pair needs them (EnsureTriBoxes)
      // Four triangles at a time: each box from its corners, then transposed into the rows (padding slots
      // have corners 0, 0, 0: a box, inverted below).
      for (uint32_t t = 0; t < kPatch; t += 4) {
        __m128 l[4], h[4];
        for (uint32_t k = 0; k < 4; ++k) {
          const uint8_t* c = corner + 3 * (t + k);
          const __m128 a = _mm_load_ps(local + 4 * c[0]), b = _mm_load_ps(local + 4 * c[1]), d = _mm_load_ps(local + 4 * c[2]);
          l[k] = _mm_min_ps(_mm_min_ps(a, b), d), h[k] = _mm_max_ps(_mm_max_ps(a, b), d);
        }
        _MM_TRANSPOSE4_PS(l[0], l[1], l[2], l[3]);
        _MM_TRANSPOSE4_PS(h[0], h[1], h[2], h[3]);
        for (int k = 0; k < 3; ++k) _mm_storeu_ps(tb + 16 * k + t, l[k]), _mm_storeu_ps(tb + 16 * (3 + k) + t, h[k]);
      }
      for (uint32_t t = m.cl_count_[p]; t < kPatch; ++t)
        for (int k = 0; k < 3; ++k) tb[16 * k + t] = kInfinity, tb[16 * (3 + k) + t] = -kInfinity;
    }
    // A NaN anywhere (min/max would drop it), or an infinite coordinate (it reaches the box of them all).
    alignas(16) float tl[4], th[4];
    _mm_store_ps(tl, all_lo), _mm_store_ps(th, all_hi);
    if (_mm_movemask_ps(nan)) return false;
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(tl[k]) || !std::isfinite(th[k])) return false;
      lo[k] = tl[k], hi[k] = th[k];
    }
#else
    for (uint32_t p = 0; p < C; ++p) {
      const uint32_t first = m.cl_vert_offsets_[p], nv = m.cl_vert_offsets_[p + 1] - first;
      const uint8_t* corner = &m.cl_local_[3 * kPatch * size_t{p}];
      const uint32_t n = m.cl_count_[p];
      float* tb = &w.patch_tri_box_[6 * kPatch * size_t{p}];
      float bl[3] = {kInfinity, kInfinity, kInfinity}, bh[3] = {-kInfinity, -kInfinity, -kInfinity};
      bool nan = false;  // std::min/max would drop a NaN
      const bool skip = kRestricted && active[p] != stamp;
      for (uint32_t i = 0; i < (skip ? 0 : nv); ++i) {
        const float* q = reinterpret_cast<const float*>(base + stride * m.cl_vert_[first + i]);
        for (int k = 0; k < 3; ++k) bl[k] = std::min(bl[k], q[k]), bh[k] = std::max(bh[k], q[k]), nan |= q[k] != q[k];
      }
      if (nan) return false;
      float* pb = box + 6 * kGroup * size_t{p / kGroup} + p % kGroup;
      float* gb = group + p / kGroup;
      // A patch collapsed onto a point or a line: no triangle with an area, no contact (the SSE2 path's comment).
      const bool collapsed = (bl[0] == bh[0]) + (bl[1] == bh[1]) + (bl[2] == bh[2]) >= 2;
      for (int k = 0; k < 3; ++k) {
        if (!skip && (!std::isfinite(bl[k]) || !std::isfinite(bh[k]))) return false;
        lo[k] = std::min(lo[k], bl[k]), hi[k] = std::max(hi[k], bh[k]);
        if (collapsed) bl[k] = kInfinity, bh[k] = -kInfinity;
        pb[kGroup * k] = bl[k], pb[kGroup * (3 + k)] = bh[k];
        if (p % kGroup == 0) gb[k * size_t{G}] = kInfinity, gb[(3 + k) * size_t{G}] = -kInfinity;
        gb[k * size_t{G}] = std::min(gb[k * size_t{G}], bl[k]), gb[(3 + k) * size_t{G}] = std::max(gb[(3 + k) * size_t{G}], bh[k]);
      }
      if (tri_boxes && !skip) TriBoxes(m, base, stride, p, tb);
    }
#endif
    return true;
  }

  /// Patch p's 16 triangle boxes (6 rows of 16, inverted padding) into `tb`, its corners read again.
  static void TriBoxes(const NarrowPhaseModel& m, const char* base, size_t stride, uint32_t p, float* tb) {
    const uint32_t first = m.cl_vert_offsets_[p], n = m.cl_count_[p];
    const uint8_t* corner = &m.cl_local_[3 * kPatch * size_t{p}];
    for (uint32_t t = 0; t < kPatch; ++t) {
      float l[3] = {kInfinity, kInfinity, kInfinity}, h[3] = {-kInfinity, -kInfinity, -kInfinity};
      if (t < n)
        for (int j = 0; j < 3; ++j) {
          const float* q = reinterpret_cast<const float*>(base + stride * m.cl_vert_[first + corner[3 * t + j]]);
          for (int k = 0; k < 3; ++k) l[k] = std::min(l[k], q[k]), h[k] = std::max(h[k], q[k]);
        }
      for (int k = 0; k < 3; ++k) tb[16 * k + t] = l[k], tb[16 * (3 + k) + t] = h[k];
    }
  }

  /// With the joint-matrix cull, patch p's triangle boxes once a frame, when a pair first needs them.
  static void EnsureTriBoxes(const NarrowPhaseModel& m, NarrowPhaseWorkspace& w, const char* base, size_t stride,
                             uint32_t p) {
    if (w.patch_tri_frame_[p] == w.frame_) return;
    w.patch_tri_frame_[p] = w.frame_;
    TriBoxes(m, base, stride, p, &w.patch_tri_box_[6 * kPatch * size_t{p}]);
  }

  /// The joint-matrix cull's frame (narrow_phase.h NarrowPhaseJob::joint_matrices): per joint pair of the
  /// model t and f, per joint the least singular value's lower bound (Gershgorin on AᵀA), per patch E.
  /// In double; each bound rounded up (t, f, E) or down (σ) into its float. Returns the matrices' largest
  /// |translation component| (a scale of the rounding margin).
  static float JointFrame(const NarrowPhaseModel& m, NarrowPhaseWorkspace& w, const float* M) {
    const uint32_t K = static_cast<uint32_t>(m.cull_pairs_.size());
    for (uint32_t k = 0; k < K; ++k) {
      const float* mj = M + kJointMatrixFloats * (m.cull_pairs_[k] >> 16);
      const float* mr = M + kJointMatrixFloats * (m.cull_pairs_[k] & 0xffffu);
      const float* anchor = &m.cull_anchor_[3 * size_t{k}];
      double t2 = 0.0, f2 = 0.0;
      for (int r = 0; r < 3; ++r) {
        double d = double{mj[4 * r + 3]} - mr[4 * r + 3];
        for (int c = 0; c < 3; ++c) {
          const double x = double{mj[4 * r + c]} - mr[4 * r + c];
          d += x * anchor[c], f2 += x * x;
        }
        t2 += d * d;
      }
      w.cull_t_[k] = static_cast<float>(std::sqrt(t2) * (1.0 + 1e-6));
      w.cull_f_[k] = static_cast<float>(std::sqrt(f2) * (1.0 + 1e-6));
    }
    float moved = 0.0f;
    for (uint32_t j = 0; j < m.cull_joint_count_; ++j) {
      const float* a = M + kJointMatrixFloats * j;
      moved = std::max({moved, std::fabs(a[3]), std::fabs(a[7]), std::fabs(a[11])});
      double g[3][3];
      for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) g[i][k] = double{a[i]} * a[k] + double{a[4 + i]} * a[4 + k] + double{a[8 + i]} * a[8 + k];
      double low = std::numeric_limits<double>::infinity();
      for (int i = 0; i < 3; ++i) low = std::min(low, g[i][i] - std::fabs(g[i][(i + 1) % 3]) - std::fabs(g[i][(i + 2) % 3]));
      w.cull_smin_[j] = low > 0.0 ? static_cast<float>(std::sqrt(low) * (1.0 - 1e-6)) : 0.0f;
    }
    const uint32_t C = PatchCount(m);
    for (uint32_t p = 0; p < C; ++p) {
      if (m.cl_ref_[p] == kNone) {
        w.cull_e_[p] = kInfinity;
        continue;
      }
      double most = 0.0, sum = 0.0;
      for (uint32_t e = m.cl_cull_offsets_[p]; e < m.cl_cull_offsets_[p + 1]; ++e) {
        const uint32_t k = m.cl_cull_pair_[e];
        const double term = double{w.cull_t_[k]} + double{w.cull_f_[k]} * m.cl_cull_reach_[e];
        most = std::max(most, term), sum += m.cl_cull_w_[e] * term;
      }
      w.cull_e_[p] = static_cast<float>(std::min(double{m.cl_slack_[p]} * most, sum) * (1.0 + 1e-6));
    }
    return moved;
  }

  /// True when the joint-matrix bound proves that no pair not near of patches a <= b (near block `block`)
  /// intersects this frame (the derivation: narrow_phase.h NarrowPhaseJob::joint_matrices).
  static bool JointCulled(const NarrowPhaseModel& m, const NarrowPhaseWorkspace& w, uint32_t a, uint32_t b,
                          uint32_t block, float margin) {
    const uint32_t r = m.cl_ref_[a];
    const float gap = m.near_gap_[block];
    if (r == kNone || m.cl_ref_[b] == kNone || !(gap > 0.0f)) return false;
    float e = w.cull_e_[a] + w.cull_e_[b] + margin;
    const uint32_t x = m.near_cross_[block];
    if (x != kNone) e += w.cull_t_[x] + w.cull_f_[x] * m.near_cross_reach_[block];
    return w.cull_smin_[r] * gap > e;
  }

  /// The sweep order (w.sweep_: group box minimum on `axis` << 32 | group, ascending). The previous frame's
  /// order, re-keyed and insertion-sorted, when it was on the same axis (frames of one animation move little:
  /// a few swaps); a full sort otherwise, or when the insertions pass a budget of 8 moves a group. Either way
  /// the unique sorted order of the keys.
  static void Order(const NarrowPhaseModel& m, NarrowPhaseWorkspace& w, int axis) {
    const uint32_t C = GroupCount(m);
    const float* row = w.group_box_.data() + axis * size_t{C};
    uint64_t* s = w.sweep_.data();
    if (axis == w.sweep_axis_) {
      for (uint32_t i = 0; i < C; ++i) {
        const uint32_t p = static_cast<uint32_t>(s[i]);
        s[i] = uint64_t{OrderedBits(row[p])} << 32 | p;
      }
      size_t budget = 8 * size_t{C};
      uint32_t i = 1;
      for (; i < C; ++i) {
        const uint64_t key = s[i];
        uint32_t j = i;
        for (; j > 0 && s[j - 1] > key && budget; --j, --budget) s[j] = s[j - 1];
        s[j] = key;
        if (!budget) break;
      }
      if (i >= C) return;
    }
    for (uint32_t p = 0; p < C; ++p) s[p] = uint64_t{OrderedBits(row[p])} << 32 | p;
    std::sort(s, s + C);
    w.sweep_axis_ = axis;
  }

  /// Patch pair (a <= b; `rows` their near bits, `far` the rows and columns with a partner not near):
  /// every triangle pair not near whose boxes overlap, tested exactly. Each side is first kept to its
  /// triangles that meet the other patch's box and have a partner not near there.
  template <class OnContact>
  static void Pair(const NarrowPhaseModel& m, NarrowPhaseWorkspace& w, const char* base, size_t stride, uint32_t a,
                   uint32_t b, const uint16_t* rows, uint32_t far, float crease, bool lazy, Counters* c,
                   OnContact& on_contact) {
    ++c->patch_pairs;
    if (lazy) EnsureTriBoxes(m, w, base, stride, a), EnsureTriBoxes(m, w, base, stride, b);
    const float* pa = w.patch_box_.data() + 6 * kGroup * size_t{a / kGroup} + a % kGroup;  // 6 rows of kGroup
    const float* pb = w.patch_box_.data() + 6 * kGroup * size_t{b / kGroup} + b % kGroup;
    const float alo[3] = {pa[0], pa[kGroup], pa[2 * kGroup]}, ahi[3] = {pa[3 * kGroup], pa[4 * kGroup], pa[5 * kGroup]};
    const float blo[3] = {pb[0], pb[kGroup], pb[2 * kGroup]}, bhi[3] = {pb[3 * kGroup], pb[4 * kGroup], pb[5 * kGroup]};
    const float* ba = &w.patch_tri_box_[6 * kPatch * size_t{a}];
    const float* bb = &w.patch_tri_box_[6 * kPatch * size_t{b}];
    uint32_t live = Overlap16(ba, blo, bhi) & far & 0xffffu;
    if (!live) return;
    const uint32_t cols = Overlap16(bb, alo, ahi) & far >> 16;
    if (!cols) return;
    const bool wider = crease > m.crease_graph_.crease();
#if SPHERECHAIN_SKIN_AVX512
    const float* fa = nullptr;
    const float* fb = nullptr;
    uint32_t certified_a = 0, certified_b = 0;
#endif
    for (; live; live &= live - 1) {
      const uint32_t i = static_cast<uint32_t>(__builtin_ctz(live));
      uint32_t want = cols & ~uint32_t{rows[i]};
      if (a == b) want &= ~((2u << i) - 1);  // each pair of one patch once (j > i)
      if (!want) continue;
      const float lo[3] = {ba[i], ba[16 + i], ba[32 + i]}, hi[3] = {ba[48 + i], ba[64 + i], ba[80 + i]};
      uint32_t overlap = Overlap16(bb, lo, hi) & want;
      c->box_tests += kPatch;
      if (!overlap) continue;
#if SPHERECHAIN_SKIN_AVX512
      // The float filter for the whole row at once: the pairs it rejects are tests the scalar path would
      // reject in the same filter (counted as tests); the others go on as there.
      if (!fa) fa = Filter(m, w, base, stride, a, &certified_a), fb = Filter(m, w, base, stride, b, &certified_b);
      if (certified_a >> i & 1) {
        if (const uint32_t rejected = FilterRejects16(fa, i, fb) & overlap & certified_b) {
          c->tests += static_cast<uint32_t>(__builtin_popcount(rejected));
          overlap &= ~rejected;
          if (!overlap) continue;
        }
      }
#endif
      const uint32_t t = m.cl_tri_[kPatch * size_t{a} + i];
      const PreparedTriangle* pt;
#if SPHERECHAIN_SKIN_AVX512
      PreparedTriangle lane_t, lane_u;  // a certified lane is what PrepareTriangle would write
      if (certified_a >> i & 1) {
        LaneToPrepared(fa, i, &lane_t);
        pt = &lane_t;
      } else
#endif
      {
        const uint32_t ts = Prepared(m, w, base, stride, t, c);
        if (ts == kNone) continue;  // t degenerate: in no contact
        pt = &w.tri_prepared_[ts];
      }
      const uint32_t* tv = &m.tri_v_[3 * size_t{t}];
      for (; overlap; overlap &= overlap - 1) {
        const uint32_t j = static_cast<uint32_t>(__builtin_ctz(overlap));
        const uint32_t u = m.cl_tri_[kPatch * size_t{b} + j];
        const PreparedTriangle* pu;
#if SPHERECHAIN_SKIN_AVX512
        if (certified_b >> j & 1) {
          LaneToPrepared(fb, j, &lane_u);
          pu = &lane_u;
        } else
#endif
        {
          const uint32_t us = Prepared(m, w, base, stride, u, c);
          if (us == kNone) continue;
          pu = &w.tri_prepared_[us];
        }
        ++c->tests;
        if (!TrianglesIntersect(*pt, *pu)) continue;
        if (wider && w.crease_scratch_.Near(m.crease_graph_, tv, &m.tri_v_[3 * size_t{u}], crease)) {
          ++c->folds;
          continue;
        }
        ++c->contacts;
        on_contact(t, u);
      }
    }
  }

  /// The sweep's budget (NarrowPhaseModel::kSweepTestsPerTriangle): InitModel's bind sweep and each job.
  static Counters SweepBudget(const NarrowPhaseModel& m) {
    Counters b;
    b.tests = SweepLimit(NarrowPhaseModel::kSweepTestsPerTriangle, m.tri_v_.size() / 3);
    b.patch_pairs = SweepLimit(NarrowPhaseModel::kSweepPairsPerPatch, PatchCount(m));
    return b;
  }
  static bool OverBudget(const Counters& c, const Counters& budget) {
    return c.tests > budget.tests || c.patch_pairs > budget.patch_pairs;
  }

  /// One frame: patch boxes, the sweep, every pair. False (nothing reported) when a patch vertex is NaN/Inf.
  /// kRestricted: only the patches with active[p] == stamp, and of their pairs those Listed (the restricted
  /// path); else every patch (active unread). `budget` (opt; SweepBudget): the sweep stops once c's
  /// exact tests or pairs of patches pass budget's (checked before each pair of groups: at most 16 pairs of
  /// patches and 4,096 tests more; the caller compares the counts after).
  template <bool kRestricted, class OnContact>
  static bool Collide(const NarrowPhaseModel& m, NarrowPhaseWorkspace& w, const char* base, size_t stride,
                      float crease, const float* joints, const uint32_t* active, uint32_t stamp, const Counters* budget,
                      Counters* c, OnContact&& on_contact) {
    const uint32_t C = GroupCount(m);
    if (++w.frame_ >= 0x7fffffffu) {  // stamps wrap: forget them all
      std::fill(w.tri_frame_.begin(), w.tri_frame_.end(), uint64_t{0});
      std::fill(w.patch_tri_frame_.begin(), w.patch_tri_frame_.end(), 0u);
      std::fill(w.patch_filter_.begin(), w.patch_filter_.end(), uint64_t{0});
      w.frame_ = 1;
    }
    w.prepared_used_ = 0;
    w.filters_used_ = 0;
    if (C == 0) return true;  // no patch (every triangle degenerate by weld ids): no vertex to read, no contact
    float lo[3], hi[3];
    const bool lazy = joints != nullptr;
    // Triangle boxes when a pair first needs them: with the joint-matrix cull, and on the restricted path.
    const bool lazy_boxes = lazy || kRestricted;
    if (!Boxes<kRestricted>(m, w, base, stride, lo, hi, !lazy_boxes, active, stamp)) return false;
    float margin = 0.0f;
    if (lazy) {  // float skinning's rounding grows with every term it adds: frame, bind pose and translations
      margin = std::max(JointFrame(m, w, joints), m.cull_bind_extent_);
      for (int k = 0; k < 3; ++k) margin = std::max(margin, std::max(std::fabs(lo[k]), std::fabs(hi[k])));
      margin *= 1e-4f;
    }
    const float* box = w.group_box_.data();
    const float* patch_box = w.patch_box_.data();
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
    Order(m, w, axis);
    // The group boxes in sweep order: the sweep's axis first, then the two others (a sentinel after the last).
    const int rows_of[6] = {axis, 3 + axis, (axis + 1) % 3, 3 + (axis + 1) % 3, (axis + 2) % 3, 3 + (axis + 2) % 3};
    float* sb = w.sweep_box_.data();
    const size_t pitch = size_t{C} + 1;
    for (uint32_t i = 0; i < C; ++i) {
      const uint32_t p = static_cast<uint32_t>(w.sweep_[i]);
      for (int r = 0; r < 6; ++r) sb[r * pitch + i] = box[rows_of[r] * size_t{C} + p];
    }
    static const uint16_t kFar[kPatch] = {};
    // Groups g and h (g == h: each pair of its patches once, a patch with itself included): unless the
    // model marks all their patch pairs to skip, their patches' boxes 4 at a time, then each overlapping
    // pair of patches not skipped whole.
    auto over_budget = [&] { return budget && OverBudget(*c, *budget); };
    auto groups = [&](uint32_t g, uint32_t h) {
      if (over_budget()) return;
      if (g > h) std::swap(g, h);
      const uint32_t skip = h - g < kGroupWindow ? m.group_near_[kGroupWindow * size_t{g} + (h - g)] : 0u;
      if (skip == 0xffffu) return;
      const float* bg = patch_box + 6 * kGroup * size_t{g};
      const float* bh = patch_box + 6 * kGroup * size_t{h};
      uint32_t overlap = 0;
      for (uint32_t j = 0; j < kGroup; ++j) {
        const float lo[3] = {bh[j], bh[kGroup + j], bh[2 * kGroup + j]};
        const float hi[3] = {bh[3 * kGroup + j], bh[4 * kGroup + j], bh[5 * kGroup + j]};
        overlap |= OverlapMask4(bg, lo, hi) << (kGroup * j);
      }
      for (overlap &= ~skip; overlap; overlap &= overlap - 1) {
        const uint32_t bit = static_cast<uint32_t>(__builtin_ctz(overlap));
        const uint32_t a = kGroup * g + bit % kGroup, b = kGroup * h + bit / kGroup;
        const uint32_t block = NearBlock(m, a, b);
        if ((kRestricted && !Listed(m, w, a, b)) || block == kAllNear) continue;
        if (block == kFarPair) {
          Pair(m, w, base, stride, a, b, kFar, m.cl_valid_[a] | m.cl_valid_[b] << 16, crease, lazy_boxes, c, on_contact);
        } else if (lazy && JointCulled(m, w, a, b, block, margin)) {
          ++c->patch_pairs, ++c->joint_culled;
        } else {
          Pair(m, w, base, stride, a, b, &m.near_rows_[kPatch * size_t{block}], m.near_far_[block], crease, lazy_boxes, c,
               on_contact);
        }
      }
    };
    for (uint32_t i = 0; i < C; ++i) {
      const uint32_t p = static_cast<uint32_t>(w.sweep_[i]);
      groups(p, p);
      const float end = sb[pitch + i], l1 = sb[2 * pitch + i], h1 = sb[3 * pitch + i], l2 = sb[4 * pitch + i],
                  h2 = sb[5 * pitch + i];
      // The groups starting before p ends on the axis, then those overlapping it on the two others
      // (branch-free: their sweep positions appended to hits_ as found).
      uint32_t n = 0;
      uint32_t* hits = w.sweep_hits_.data();
      uint32_t j = i + 1;
#if SPHERECHAIN_SKIN_SSE2
      const __m128 vl1 = _mm_set1_ps(l1), vh1 = _mm_set1_ps(h1), vl2 = _mm_set1_ps(l2), vh2 = _mm_set1_ps(h2);
      const __m128 vend = _mm_set1_ps(end);
      for (; j + 4 <= C; j += 4) {
        const __m128 start = _mm_loadu_ps(sb + j);
        const __m128 mk = _mm_and_ps(_mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(sb + 2 * pitch + j), vh1),
                                                _mm_cmpge_ps(_mm_loadu_ps(sb + 3 * pitch + j), vl1)),
                                     _mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(sb + 4 * pitch + j), vh2),
                                                _mm_cmpge_ps(_mm_loadu_ps(sb + 5 * pitch + j), vl2)));
        const int in = _mm_movemask_ps(_mm_cmple_ps(start, vend));
        for (uint32_t bits = static_cast<uint32_t>(_mm_movemask_ps(mk) & in); bits; bits &= bits - 1)
          hits[n++] = j + static_cast<uint32_t>(__builtin_ctz(bits));
        if (in != 0xf) break;  // sorted: the rest start after p ends
      }
      if (j + 4 > C)
#endif
        for (; j < C && sb[j] <= end; ++j) {
          hits[n] = j;
          n += (sb[2 * pitch + j] <= h1) & (sb[3 * pitch + j] >= l1) & (sb[4 * pitch + j] <= h2) & (sb[5 * pitch + j] >= l2);
        }
      for (uint32_t k = 0; k < n; ++k) groups(p, static_cast<uint32_t>(w.sweep_[hits[k]]));
      if (over_budget()) return true;
    }
    return true;
  }

  /// Model part: the index buffer, the graph, the patches and the bind pose's own contacts.
  static Status InitModel(NarrowPhaseModel& m, const AssetView& view) {
    const schema::Asset& a = *view.asset;
    const auto* bind = a.bind_positions();
    if (!bind || !(a.crease() > 0.0f)) return Status::kOk;  // no crease rule: kCrease jobs refused
    const auto* tris = a.triangles();
    m.tri_v_.assign(tris->begin(), tris->end());
    if (Status s = m.crease_graph_.Init(bind->data(), view.vertex_count, m.tri_v_.data(), view.triangle_count,
                                        m.weld_.data(), a.crease());
        s != Status::kOk)
      return s;
    if (Status s = BuildPatches(m, bind->data()); s != Status::kOk) return s;
    BuildJointCull(m, a, bind->data());
    NarrowPhaseWorkspace w;
    if (Status s = InitWorkspace(w, m, nullptr); s != Status::kOk) return s;
    // The bind pose's own contacts, within the sweep's budget.
    const Counters budget = SweepBudget(m);
    Counters c;
    Collide<false>(m, w, reinterpret_cast<const char*>(bind->data()), 12, m.crease_graph_.crease(), nullptr, nullptr, 0,
                   &budget, &c,
                   [&](uint32_t t, uint32_t u) { m.bind_contacts_.push_back(uint64_t{std::min(t, u)} << 32 | std::max(t, u)); });
    if (OverBudget(c, budget)) return Status::kErrorBindPoseTangled;
    std::sort(m.bind_contacts_.begin(), m.bind_contacts_.end());
    BuildRestricted(m, a);
    return Status::kOk;
  }

  /// The restricted path's model part (NarrowPhaseModel: sphere_patches_ … fold_bind_distance_).
  static void BuildRestricted(NarrowPhaseModel& m, const schema::Asset& a) {
    const uint32_t S = m.sphere_count_, T = static_cast<uint32_t>(m.tri_v_.size() / 3);
    std::vector<uint32_t> patch_of(T, kNone), list;
    for (size_t k = 0; k < m.cl_tri_.size(); ++k)
      if (m.cl_tri_[k] != kNone) patch_of[m.cl_tri_[k]] = static_cast<uint32_t>(k / kPatch);
    auto sorted = [&list] {
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
    };
    m.sphere_patch_offsets_.assign(1, 0);
    m.sphere_patches_.clear();
    for (uint32_t s = 0; s < S; ++s) {  // the model's regions: reach or surrounding (degenerate triangles left out)
      list.clear();
      for (uint32_t k = m.region_offsets_[s]; k < m.region_offsets_[s + 1]; ++k)
        if (const uint32_t p = patch_of[m.region_tri_[k]]; p != kNone) list.push_back(p);
      sorted();
      m.sphere_patches_.insert(m.sphere_patches_.end(), list.begin(), list.end());
      m.sphere_patch_offsets_.push_back(static_cast<uint32_t>(m.sphere_patches_.size()));
    }
    const size_t words = SphereWords(m);
    m.patch_sphere_bits_.assign(size_t{PatchCount(m)} * words, 0);
    for (uint32_t s = 0; s < S; ++s)
      for (uint32_t k = m.sphere_patch_offsets_[s]; k < m.sphere_patch_offsets_[s + 1]; ++k)
        m.patch_sphere_bits_[m.sphere_patches_[k] * words + s / 64] |= uint64_t{1} << (s % 64);
    list.clear();
    for (uint64_t key : m.bind_contacts_)
      for (uint32_t t : {static_cast<uint32_t>(key >> 32), static_cast<uint32_t>(key)})
        if (patch_of[t] != kNone) list.push_back(patch_of[t]);
    sorted();
    m.bind_patches_.assign(list.begin(), list.end());
    m.patch_bind_.assign(PatchCount(m), 0);
    for (uint32_t p : list) m.patch_bind_[p] = 1;
    m.fold_pairs_.clear();
    m.fold_bind_distance_.clear();
    if (const auto* ex = a.excluded_pairs(); ex && a.spheres())
      for (const schema::SpherePair* p : *ex) {
        const schema::Vec3& ca = a.spheres()->Get(p->a())->center();
        const schema::Vec3& cb = a.spheres()->Get(p->b())->center();
        const float dx = ca.x() - cb.x(), dy = ca.y() - cb.y(), dz = ca.z() - cb.z();
        m.fold_pairs_.push_back(uint32_t{p->a()} << 16 | p->b());
        m.fold_bind_distance_.push_back(std::sqrt(dx * dx + dy * dy + dz * dz));
      }
  }

  static Status InitWorkspace(NarrowPhaseWorkspace& w, const NarrowPhaseModel& m, BlockArena* arena) {
    if (!m.crease_graph_.initialized()) return Status::kOk;
    const uint32_t C = GroupCount(m), T = static_cast<uint32_t>(m.tri_v_.size() / 3);
    w.patch_box_.assign(6 * kGroup * size_t{C}, 0.0f);
    for (size_t g = 0; g < C; ++g)  // inverted: the padding patches of the last group (never written)
      for (uint32_t k = 0; k < 3 * kGroup; ++k) w.patch_box_[6 * kGroup * g + k] = kInfinity, w.patch_box_[6 * kGroup * g + 3 * kGroup + k] = -kInfinity;
    w.group_box_.assign(6 * size_t{C}, 0.0f);
    w.sweep_.assign(C, 0);
    w.sweep_box_.assign(6 * (size_t{C} + 1), 0.0f);
    w.sweep_hits_.assign(size_t{C} + 1, 0);
    for (uint32_t p = 0; p < C; ++p) w.sweep_[p] = p;
    w.sweep_axis_ = -1;
    w.patch_tri_box_.assign(96 * size_t{PatchCount(m)}, 0.0f);
    w.tri_prepared_.assign(T, PreparedTriangle{});
    w.tri_frame_.assign(T, 0);
    // The AVX-512 copy's 16-lane float filter (Filter): sized only where that copy runs (kernels::Best() is
    // fixed for the process), at most one slot a patch a frame.
    const size_t filter_patches = kernels::Best() == kernels::Isa::kAvx512 ? PatchCount(m) : 0;
    w.filter_pool_.assign(kFilterFloats * filter_patches, 0.0f);
    w.filter_mask_.assign(filter_patches, 0);
    w.patch_filter_.assign(filter_patches, 0);
    w.frame_ = 0;
    w.cull_t_.assign(m.cull_pairs_.size(), 0.0f);
    w.cull_f_.assign(m.cull_pairs_.size(), 0.0f);
    w.cull_smin_.assign(m.cull_joint_count_, 0.0f);
    w.cull_e_.assign(m.cull_joint_count_ ? PatchCount(m) : 0, 0.0f);
    w.patch_tri_frame_.assign(PatchCount(m), 0u);
    w.patch_active_.assign(PatchCount(m), 0u);
    w.patch_partner_bits_.assign(size_t{PatchCount(m)} * SphereWords(m), 0u);
    w.active_stamp_ = 0;
    return w.crease_scratch_.Init(m.crease_graph_, arena);
  }

  static Status Run(const NarrowPhaseJob& job) {
    const NarrowPhaseModel& m = *job.model;
    NarrowPhaseWorkspace& w = *job.workspace;
    NarrowPhaseStats st;
    *job.count = 0;
    if (job.stats) *job.stats = st;
    const float crease = job.crease > 0.0f ? job.crease : m.crease_graph_.crease();
    w.crease_scratch_.Reset();
    Counters c;
    uint32_t written = 0;
    const char* base = static_cast<const char*>(job.positions.data);
    const size_t stride = job.positions.stride_bytes;
    if (job.joint_matrices)
      for (size_t i = 0; i < size_t{job.joint_count} * kJointMatrixFloats; ++i)
        if (!std::isfinite(job.joint_matrices[i])) return Status::kErrorNonFiniteJoints;
    // The restricted path: the patches behind the listed spheres, and those of the bind pose's contacts.
    const uint32_t* active = nullptr;
    uint32_t stamp = 0, swept = 0;
    if (job.sphere_pairs) {
      if (++w.active_stamp_ == 0) {  // stamps wrap: forget them all
        std::fill(w.patch_active_.begin(), w.patch_active_.end(), 0u);
        w.active_stamp_ = 1;
      }
      stamp = w.active_stamp_;
      const size_t words = SphereWords(m);
      // Each patch behind a listed sphere: swept, its partner bits the spheres listed with one of its
      // spheres, and those spheres themselves (a listed sphere is its own partner).
      auto patch = [&](uint32_t p) -> uint64_t* {
        uint64_t* bits = &w.patch_partner_bits_[p * words];
        if (w.patch_active_[p] != stamp) {
          ++swept;
          w.patch_active_[p] = stamp;
          std::fill(bits, bits + words, uint64_t{0});
        }
        return bits;
      };
      for (uint32_t i = 0; i < job.sphere_pair_count; ++i) {
        const uint32_t pair[2] = {job.sphere_pairs[i].a, job.sphere_pairs[i].b};
        for (int side = 0; side < 2; ++side) {
          const uint32_t s = pair[side], t = pair[1 - side];
          for (uint32_t k = m.sphere_patch_offsets_[s]; k < m.sphere_patch_offsets_[s + 1]; ++k) {
            uint64_t* bits = patch(m.sphere_patches_[k]);
            bits[t / 64] |= uint64_t{1} << (t % 64);
            bits[s / 64] |= uint64_t{1} << (s % 64);
          }
        }
      }
      for (uint32_t p : m.bind_patches_) patch(p);
      active = w.patch_active_.data();
    }
    auto on_contact = [&](uint32_t t, uint32_t u) {
      st.bind_contacts += m.IntersectsAtBind(t, u);
      if (written >= job.capacity) return;
      uint16_t sa = m.tri_sphere_[t], sb = m.tri_sphere_[u];
      if (sa > sb || (sa == sb && t > u)) std::swap(sa, sb), std::swap(t, u);
      if (job.depths) {
        const float* pa[3];
        const float* pb[3];
        for (int j = 0; j < 3; ++j) {
          pa[j] = reinterpret_cast<const float*>(base + stride * m.tri_v_[3 * size_t{t} + j]);
          pb[j] = reinterpret_cast<const float*>(base + stride * m.tri_v_[3 * size_t{u} + j]);
        }
        ContactDepthOf(pa, pb, &job.depths[written]);
      }
      job.output[written++] = TriangleContact{t, u, sa, sb};
    };
    const Counters budget = SweepBudget(m);
    const bool finite = active ? swept == 0 ||  // nothing to sweep: no vertex read, no contact
                                     Collide<true>(m, w, base, stride, crease, job.joint_matrices, active, stamp, &budget, &c,
                                                   on_contact)
                               : Collide<false>(m, w, base, stride, crease, job.joint_matrices, nullptr, 0, &budget, &c, on_contact);
    if (!finite) return Status::kErrorNonFinitePositions;
    st.candidate_pairs = c.patch_pairs;
    st.box_tests = c.box_tests;
    st.triangle_tests = c.tests;
    st.degenerate_triangles = c.degenerate;
    st.crease_folds = c.folds;
    st.contacts = c.contacts;
    st.joint_culled = c.joint_culled;
    if (job.stats) *job.stats = st;
    if (OverBudget(c, budget)) return Status::kErrorFrameTangled;  // no pose: stopped, count 0
    *job.count = written;
    return st.contacts > job.capacity ? Status::kOkTruncated : Status::kOk;
  }
