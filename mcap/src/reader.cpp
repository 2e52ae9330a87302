// SPDX-License-Identifier: Apache-2.0
#include "sim/mcap/reader.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <set>
#include <vector>

#include "bytes.hpp"
#include "codec.hpp"

namespace sim::mcap {

namespace {

constexpr std::size_t kRecordPrefix = 1 + 8;           // opcode + content length
constexpr std::size_t kFooterRecord = kRecordPrefix + 20;
constexpr std::size_t kMessagePrefix = 2 + 4 + 8 + 8;  // channel, sequence, two times

std::string at(std::uint64_t offset) { return " at byte " + std::to_string(offset); }

bool is_magic(std::span<const std::byte> bytes) {
  return bytes.size() >= kMagic.size() &&
         std::memcmp(bytes.data(), kMagic.data(), kMagic.size()) == 0;
}

std::optional<Schema> parse_schema(std::span<const std::byte> content) {
  detail::ByteReader r(content);
  Schema s;
  s.id = r.get<std::uint16_t>();
  s.name = r.string();
  s.encoding = r.string();
  const auto data = r.string();
  s.data = data;
  if (r.failed() || s.id == 0) return std::nullopt;
  return s;
}

std::optional<Channel> parse_channel(std::span<const std::byte> content) {
  detail::ByteReader r(content);
  Channel c;
  c.id = r.get<std::uint16_t>();
  c.schema_id = r.get<std::uint16_t>();
  c.topic = r.string();
  c.message_encoding = r.string();
  const auto map_bytes = r.get<std::uint32_t>();
  detail::ByteReader m(r.bytes(map_bytes));
  while (!r.failed() && !m.failed() && m.remaining() > 0) {
    std::string key(m.string());
    std::string value(m.string());
    if (!m.failed()) c.metadata.emplace(std::move(key), std::move(value));
  }
  if (r.failed() || m.failed()) return std::nullopt;
  return c;
}

std::optional<Statistics> parse_statistics(std::span<const std::byte> content) {
  detail::ByteReader r(content);
  Statistics s;
  s.message_count = r.get<std::uint64_t>();
  s.schema_count = r.get<std::uint16_t>();
  s.channel_count = r.get<std::uint32_t>();
  s.attachment_count = r.get<std::uint32_t>();
  s.metadata_count = r.get<std::uint32_t>();
  s.chunk_count = r.get<std::uint32_t>();
  s.message_start_time = r.get<std::uint64_t>();
  s.message_end_time = r.get<std::uint64_t>();
  const auto map_bytes = r.get<std::uint32_t>();
  detail::ByteReader m(r.bytes(map_bytes));
  while (!r.failed() && !m.failed() && m.remaining() > 0) {
    const auto id = m.get<std::uint16_t>();
    const auto count = m.get<std::uint64_t>();
    if (!m.failed()) s.channel_message_counts[id] = count;
  }
  if (r.failed() || m.failed()) return std::nullopt;
  return s;
}

std::optional<MessageView> parse_message(std::span<const std::byte> content) {
  if (content.size() < kMessagePrefix) return std::nullopt;
  detail::ByteReader r(content);
  MessageView v;
  v.header.channel_id = r.get<std::uint16_t>();
  v.header.sequence = r.get<std::uint32_t>();
  v.header.log_time = r.get<std::uint64_t>();
  v.header.publish_time = r.get<std::uint64_t>();
  v.data = r.rest();
  return v;
}

}  // namespace

struct Reader::Impl {
  void* mapping = nullptr;
  std::size_t mapping_size = 0;
  std::span<const std::byte> file;

  std::string profile;
  std::string library;
  std::map<std::uint16_t, Schema> schemas;
  std::map<std::uint16_t, Channel> channels;
  std::optional<Statistics> statistics;
  bool has_summary = false;
  bool has_footer = false;       // the file ends with an intact Footer and magic
  bool channels_known = false;   // every Channel record of the file has been read
  std::optional<std::uint64_t> earliest_log_time;  // of the messages delivered so far
  std::optional<std::uint64_t> start_time;         // the file's earliest log time, when known

  std::size_t data_end = 0;  // where the data section stops being read
  std::size_t pos = 0;
  bool finished = false;
  std::uint32_t data_crc = 0;  // running CRC from the file's first byte to `pos`
  bool data_end_seen = false;  // this pass met the Data End record
  std::uint64_t messages_seen = 0;  // Message records met in this pass, intact or not

  std::unique_ptr<std::byte[]> chunk_buffer;
  std::size_t chunk_capacity = 0;
  std::span<const std::byte> chunk;  // the current chunk's records
  std::size_t chunk_offset = 0;      // where the current chunk's record starts in the file
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order;  // (log time, record offset)
  std::size_t order_next = 0;

  std::string problem;
  std::set<std::string> problems;
  std::set<std::size_t> skipped_chunks;

  ~Impl() {
    if (mapping != nullptr) ::munmap(mapping, mapping_size);
  }

  void note(std::string sentence) {
    if (problem.empty()) problem = sentence;
    problems.insert(std::move(sentence));
  }
  void skip_chunk(std::size_t offset, const std::string& why) {
    note("the chunk" + at(offset) + " " + why + "; its messages were skipped");
    skipped_chunks.insert(offset);
  }

  // A Schema or Channel may be repeated (the summary copies them) but never redefined: the
  // first definition stays, and a different one with the same id is damage worth a sentence.
  void add_schema(std::span<const std::byte> content, std::size_t offset) {
    auto s = parse_schema(content);
    if (!s) {
      note("the schema record" + at(offset) + " is malformed; messages that need it cannot be decoded");
      return;
    }
    const auto [it, added] = schemas.try_emplace(s->id, *s);
    if (!added && (it->second.name != s->name || it->second.encoding != s->encoding ||
                   it->second.data != s->data)) {
      note("the schema record" + at(offset) + " redefines schema id " + std::to_string(s->id) +
           " differently, which MCAP forbids; the first definition is used");
    }
  }
  void add_channel(std::span<const std::byte> content, std::size_t offset) {
    auto c = parse_channel(content);
    if (!c) {
      note("the channel record" + at(offset) + " is malformed; its messages are skipped");
      return;
    }
    const auto [it, added] = channels.try_emplace(c->id, *c);
    if (!added && (it->second.topic != c->topic || it->second.schema_id != c->schema_id ||
                   it->second.message_encoding != c->message_encoding)) {
      note("the channel record" + at(offset) + " redefines channel id " + std::to_string(c->id) +
           " (topic " + printable(c->topic) + ") differently, which MCAP forbids; its messages "
           "play as the first definition (topic " + printable(it->second.topic) + ")");
    }
  }

  // Whether the summary repeats every Channel and the Schema of each: writers may leave them out
  // (the summary is optional, and so are its copies), and then the data section must be read.
  bool summary_lists_every_channel() const {
    if (channels.empty()) return false;
    return std::all_of(channels.begin(), channels.end(), [&](const auto& entry) {
      return entry.second.schema_id == 0 || schemas.count(entry.second.schema_id) > 0;
    });
  }

  // Reads the Footer, and the summary it points to, when the file ends as it should.
  void read_summary() {
    const std::size_t size = file.size();
    if (size < kMagic.size() * 2 + kFooterRecord || !is_magic(file.subspan(size - kMagic.size()))) {
      note("the file does not end with MCAP's closing magic, so it was cut short (an interrupted "
           "recording?); reading the part that is intact");
      data_end = size;
      return;
    }
    const std::size_t footer = size - kMagic.size() - kFooterRecord;
    detail::ByteReader f(file.subspan(footer, kFooterRecord));
    const auto op = f.get<std::uint8_t>();
    const auto length = f.get<std::uint64_t>();
    const auto summary_start = f.get<std::uint64_t>();
    const auto summary_offset_start = f.get<std::uint64_t>();
    const auto summary_crc = f.get<std::uint32_t>();
    if (op != static_cast<std::uint8_t>(Opcode::footer) || length != 20) {
      note("the file's footer is damaged; reading the data section without its summary");
      data_end = size;
      return;
    }
    data_end = footer;
    has_footer = true;
    if (summary_start == 0) return;  // a file without a summary is valid MCAP
    if (summary_start < kMagic.size() || summary_start > footer ||
        (summary_offset_start != 0 &&
         (summary_offset_start < summary_start || summary_offset_start > footer))) {
      note("the footer points outside the file; reading the data section without its summary");
      return;
    }
    data_end = static_cast<std::size_t>(summary_start);
    const auto summary = file.subspan(data_end, footer + kRecordPrefix + 16 - data_end);
    if (summary_crc != 0 && detail::crc32(summary) != summary_crc) {
      note("the summary fails its CRC check; reading the data section without it");
      return;
    }
    const std::size_t summary_end =
        summary_offset_start != 0 ? static_cast<std::size_t>(summary_offset_start) : footer;
    std::map<std::uint16_t, Schema> found_schemas;
    std::map<std::uint16_t, Channel> found_channels;
    std::optional<Statistics> found_statistics;
    std::size_t p = data_end;
    while (p < summary_end) {
      if (summary_end - p < kRecordPrefix) break;
      detail::ByteReader r(file.subspan(p, summary_end - p));
      const auto record_op = static_cast<Opcode>(r.get<std::uint8_t>());
      const auto content = r.bytes(r.get<std::uint64_t>());
      if (r.failed()) {
        note("the summary" + at(p) + " is malformed; reading the data section without it");
        return;
      }
      bool ok = true;
      if (record_op == Opcode::schema) {
        auto s = parse_schema(content);
        ok = s.has_value();
        if (ok) found_schemas.try_emplace(s->id, std::move(*s));
      } else if (record_op == Opcode::channel) {
        auto c = parse_channel(content);
        ok = c.has_value();
        if (ok) found_channels.try_emplace(c->id, std::move(*c));
      } else if (record_op == Opcode::statistics) {
        found_statistics = parse_statistics(content);
        ok = found_statistics.has_value();
      }
      if (!ok) {
        note("the summary record" + at(p) + " is malformed; reading the data section without it");
        return;
      }
      p += kRecordPrefix + content.size();
    }
    schemas = std::move(found_schemas);
    channels = std::move(found_channels);
    statistics = std::move(found_statistics);
    has_summary = true;
  }

  // Decompresses and checks one chunk, then lists its messages in log-time order.
  void open_chunk(std::span<const std::byte> content, std::size_t offset) {
    chunk = {};
    order.clear();
    order_next = 0;
    detail::ByteReader r(content);
    r.get<std::uint64_t>();  // message start time
    r.get<std::uint64_t>();  // message end time
    const auto uncompressed_size = r.get<std::uint64_t>();
    const auto uncompressed_crc = r.get<std::uint32_t>();
    const auto compression_name = r.string();
    const auto records = r.bytes(r.get<std::uint64_t>());
    if (r.failed()) return skip_chunk(offset, "is malformed (its fields overrun it)");
    const auto compression = parse_compression(compression_name);
    if (!compression) {
      return skip_chunk(offset, "uses compression \"" + printable(compression_name) +
                                    "\", which SIM cannot read (zstd, lz4 or none)");
    }
    if (uncompressed_size > kMaxChunkBytes) {
      return skip_chunk(offset, "claims " + std::to_string(uncompressed_size) +
                                    " bytes uncompressed, more than any sane chunk");
    }
    if (*compression == Compression::none) {
      if (records.size() != uncompressed_size) {
        return skip_chunk(offset, "holds fewer bytes than it declares");
      }
      chunk = records;
    } else {
      if (*compression == Compression::zstd) {
        const auto declared = ZSTD_getFrameContentSize(records.data(), records.size());
        if (declared != ZSTD_CONTENTSIZE_UNKNOWN && declared != uncompressed_size) {
          return skip_chunk(offset, "cannot be decompressed (its sizes disagree)");
        }
      }
      const auto n = static_cast<std::size_t>(uncompressed_size);
      if (n > chunk_capacity) {
        chunk_buffer.reset(new std::byte[n]);  // not zeroed: every byte is decompressed into
        chunk_capacity = n;
      }
      const std::string why =
          detail::decompress(*compression, records, std::span(chunk_buffer.get(), n));
      if (!why.empty()) return skip_chunk(offset, "cannot be decompressed (" + why + ")");
      chunk = std::span<const std::byte>(chunk_buffer.get(), n);
    }
    if (uncompressed_crc != 0 && detail::crc32(chunk) != uncompressed_crc) {
      chunk = {};
      return skip_chunk(offset, "fails its CRC check (the file is damaged)");
    }
    std::size_t p = 0;
    while (p < chunk.size()) {
      detail::ByteReader rr(chunk.subspan(p));
      const auto op = static_cast<Opcode>(rr.get<std::uint8_t>());
      const auto record = rr.bytes(rr.get<std::uint64_t>());
      if (rr.failed()) {
        note("the chunk" + at(offset) + " holds a record that overruns it; the rest of that chunk "
             "was skipped");
        break;
      }
      if (op == Opcode::schema) add_schema(record, offset);
      if (op == Opcode::channel) add_channel(record, offset);
      if (op == Opcode::chunk) {
        note("the chunk" + at(offset) + " holds another chunk, which MCAP does not allow; the "
             "inner chunk was skipped");
      }
      if (op == Opcode::message) {
        ++messages_seen;
        if (record.size() < kMessagePrefix) {
          note("the message" + at(offset) + " is too short to be one; it was skipped");
        } else if (p <= UINT32_MAX) {
          std::uint64_t log_time;
          std::memcpy(&log_time, record.data() + 6, sizeof log_time);
          order.emplace_back(log_time, static_cast<std::uint32_t>(p));
        }
      }
      p += kRecordPrefix + record.size();
    }
    std::stable_sort(order.begin(), order.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
  }

  // A message on a channel the file defines; one on an undefined channel is damage (noted) and
  // is not delivered, since nobody could know what it holds.
  std::optional<MessageView> deliver(std::optional<MessageView> m, std::size_t offset) {
    if (!m) return m;
    if (channels_known && channels.count(m->header.channel_id) == 0) {
      note("the message" + at(offset) + " is on channel " + std::to_string(m->header.channel_id) +
           ", which the file never defines; such messages were skipped");
      return std::nullopt;
    }
    earliest_log_time = std::min(earliest_log_time.value_or(UINT64_MAX), m->header.log_time);
    return m;
  }

  // At the end of a pass over the data section: what a whole file would have shown.
  void check_pass_complete() {
    if (has_footer && !data_end_seen && pos >= data_end) {
      note("the data section ends" + at(data_end) + " without its Data End record (the file is "
           "damaged), so its CRC could not be checked");
    }
    if (statistics && messages_seen < statistics->message_count) {
      note("the summary counts " + std::to_string(statistics->message_count) + " messages but only " +
           std::to_string(messages_seen) + " were found (the file is damaged where the others were)");
    }
  }

  std::optional<MessageView> next() {
    for (;;) {
      if (order_next < order.size()) {
        const std::uint32_t p = order[order_next++].second;
        std::uint64_t length;
        std::memcpy(&length, chunk.data() + p + 1, sizeof length);
        auto m = deliver(parse_message(chunk.subspan(p + kRecordPrefix, static_cast<std::size_t>(length))),
                         chunk_offset);
        if (m) return m;
        continue;
      }
      if (finished) return std::nullopt;
      if (pos >= data_end) {
        finished = true;
        check_pass_complete();
        continue;
      }
      if (data_end - pos < kRecordPrefix) {
        note("the file ends in the middle of a record" + at(pos) +
             ", so it was cut short; everything before it was read");
        finished = true;
        continue;
      }
      const auto op = static_cast<Opcode>(file[pos]);
      std::uint64_t length;
      std::memcpy(&length, file.data() + pos + 1, sizeof length);
      if (length > data_end - pos - kRecordPrefix) {
        note("the record" + at(pos) + " claims " + std::to_string(length) +
             " bytes but the file ends first, so it was cut short; everything before it was read");
        finished = true;
        continue;
      }
      const std::size_t record_start = pos;
      const auto content = file.subspan(pos + kRecordPrefix, static_cast<std::size_t>(length));
      pos += kRecordPrefix + content.size();
      if (op == Opcode::data_end) {
        detail::ByteReader r(content);
        const auto stored = r.get<std::uint32_t>();
        if (!r.failed() && stored != 0 && stored != data_crc) {
          note("the data section fails its CRC check (the file is damaged); intact chunks were read");
        }
        data_end_seen = true;
        finished = true;
        check_pass_complete();
        continue;
      }
      data_crc = detail::crc32(file.subspan(record_start, pos - record_start), data_crc);
      switch (op) {
        case Opcode::invalid:
          note("the record" + at(record_start) + " has opcode 0, so the file is damaged there; "
               "everything before it was read");
          finished = true;
          break;
        case Opcode::schema: add_schema(content, record_start); break;
        case Opcode::channel: add_channel(content, record_start); break;
        case Opcode::chunk:
          chunk_offset = record_start;
          open_chunk(content, record_start);
          break;
        case Opcode::message:
          ++messages_seen;
          if (auto m = parse_message(content)) {
            if (auto delivered = deliver(std::move(m), record_start)) return delivered;
          } else {
            note("the message" + at(record_start) + " is too short to be one; it was skipped");
          }
          break;
        case Opcode::footer:
          // The real Footer is past data_end: this one is a damaged record. Its length still
          // holds, so reading goes on after it.
          note("a Footer record" + at(record_start) + " lies inside the data section, so the file "
               "is damaged there; the records around it were read");
          break;
        default: break;  // header, indexes, attachments, metadata: nothing to play
      }
    }
  }

  void rewind() {
    pos = kMagic.size();
    data_crc = detail::crc32(file.subspan(0, kMagic.size()));
    finished = false;
    data_end_seen = false;
    messages_seen = 0;
    chunk = {};
    order.clear();
    order_next = 0;
  }
};

Reader::Reader(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
Reader::Reader(Reader&&) noexcept = default;
Reader& Reader::operator=(Reader&&) noexcept = default;
Reader::~Reader() = default;

Expected<Reader> Reader::from_bytes(std::span<const std::byte> bytes) {
  auto impl = std::make_unique<Impl>();
  impl->file = bytes;
  if (!is_magic(bytes)) {
    return Error{ErrorCode::invalid_argument,
                 "the file does not start with MCAP's magic bytes, so it is not an MCAP recording "
                 "(or its start is damaged)"};
  }
  // The Header record comes first; a file without one still has messages worth reading.
  detail::ByteReader h(bytes.subspan(kMagic.size()));
  if (static_cast<Opcode>(h.get<std::uint8_t>()) == Opcode::header) {
    detail::ByteReader content(h.bytes(h.get<std::uint64_t>()));
    impl->profile = content.string();
    impl->library = content.string();
  }
  impl->read_summary();
  impl->rewind();
  if (!impl->has_summary || !impl->summary_lists_every_channel()) {
    // Without them in the summary, the channels are only known by reading the data section once.
    while (impl->next()) {
    }
    impl->rewind();
    impl->start_time = impl->earliest_log_time;
  } else if (impl->statistics && impl->statistics->message_count > 0) {
    impl->start_time = impl->statistics->message_start_time;
  }
  impl->channels_known = true;
  return Reader(std::move(impl));
}

Expected<Reader> Reader::open(const std::string& path) {
  // O_NONBLOCK: a FIFO must not block the open (it is refused below); a regular file ignores it.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    return Error{errno == ENOENT ? ErrorCode::not_found : ErrorCode::system_error,
                 "cannot open " + path + ": " + std::strerror(errno) + "; check the path"};
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return Error{ErrorCode::invalid_argument, path + " is not a regular file; give an .mcap file"};
  }
  const auto size = static_cast<std::size_t>(st.st_size);
  void* mapping = nullptr;
  if (size > 0) {
    mapping = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
    if (mapping == MAP_FAILED) {
      const int err = errno;
      ::close(fd);
      return Error{ErrorCode::system_error,
                   "cannot map " + path + " into memory: " + std::strerror(err)};
    }
    ::madvise(mapping, size, MADV_SEQUENTIAL);
  }
  ::close(fd);
  auto reader = from_bytes(std::span(static_cast<const std::byte*>(mapping), size));
  if (!reader) {
    if (mapping != nullptr) ::munmap(mapping, size);
    return Error{reader.error().code, path + ": " + reader.error().message};
  }
  reader->impl_->mapping = mapping;
  reader->impl_->mapping_size = size;
  return reader;
}

const std::string& Reader::profile() const noexcept { return impl_->profile; }
const std::string& Reader::library() const noexcept { return impl_->library; }
const std::map<std::uint16_t, Schema>& Reader::schemas() const noexcept { return impl_->schemas; }
const std::map<std::uint16_t, Channel>& Reader::channels() const noexcept { return impl_->channels; }
const Schema* Reader::schema_of(const Channel& channel) const noexcept {
  const auto it = impl_->schemas.find(channel.schema_id);
  return it == impl_->schemas.end() ? nullptr : &it->second;
}
const std::optional<Statistics>& Reader::statistics() const noexcept { return impl_->statistics; }
std::optional<std::uint64_t> Reader::start_time() const noexcept { return impl_->start_time; }
bool Reader::has_summary() const noexcept { return impl_->has_summary; }
std::optional<MessageView> Reader::next() { return impl_->next(); }
void Reader::rewind() { impl_->rewind(); }
const std::string& Reader::problem() const noexcept { return impl_->problem; }
std::uint64_t Reader::problem_count() const noexcept { return impl_->problems.size(); }
std::uint64_t Reader::skipped_chunks() const noexcept { return impl_->skipped_chunks.size(); }

}  // namespace sim::mcap
