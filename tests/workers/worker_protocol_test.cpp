// Frames over a real pipe: round trips, and the errors a broken stream gives.
#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "robodiff/workers/worker_protocol.hpp"

namespace robodiff::workers {
namespace {

class Pipe {
 public:
  Pipe() {
    if (::pipe2(fds_, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
  }
  ~Pipe() {
    closeRead();
    closeWrite();
  }
  int read() const { return fds_[0]; }
  int write() const { return fds_[1]; }
  void closeRead() {
    if (fds_[0] >= 0) ::close(fds_[0]);
    fds_[0] = -1;
  }
  void closeWrite() {
    if (fds_[1] >= 0) ::close(fds_[1]);
    fds_[1] = -1;
  }
  void writeRaw(const std::string& bytes) const {
    ASSERT_EQ(::write(fds_[1], bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  }

 private:
  int fds_[2] = {-1, -1};
};

std::string lengthPrefix(std::uint32_t n) {
  return std::string{static_cast<char>(n & 0xff), static_cast<char>((n >> 8) & 0xff),
                     static_cast<char>((n >> 16) & 0xff), static_cast<char>((n >> 24) & 0xff)};
}

TEST(WorkerProtocol, FramesRoundTripThroughAPipe) {
  Pipe pipe;
  writeFrame(pipe.write(), R"({"id":1,"type":"ping"})");
  writeFrame(pipe.write(), "");
  writeFrame(pipe.write(), std::string("\0binary\xff", 8));
  pipe.closeWrite();
  EXPECT_EQ(readFrame(pipe.read()), std::optional<std::string>(R"({"id":1,"type":"ping"})"));
  EXPECT_EQ(readFrame(pipe.read()), std::optional<std::string>(""));
  EXPECT_EQ(readFrame(pipe.read()), std::optional<std::string>(std::string("\0binary\xff", 8)));
  EXPECT_EQ(readFrame(pipe.read()), std::nullopt) << "end of file between frames is a clean end";
}

TEST(WorkerProtocol, LengthIsFourBytesLittleEndian) {
  const std::string frame = encodeFrame(std::string(0x0102, 'x'));
  ASSERT_EQ(frame.size(), 4u + 0x0102);
  EXPECT_EQ(frame.substr(0, 4), std::string("\x02\x01\x00\x00", 4));
}

TEST(WorkerProtocol, AFrameLargerThanThePipeCrossesItWhole) {
  // 1 MiB: many times a pipe's buffer, so both sides see short reads and writes.
  std::string big(1 << 20, '\0');
  for (std::size_t i = 0; i < big.size(); ++i) big[i] = static_cast<char>('a' + i % 26);
  Pipe pipe;
  std::thread writer([&] { writeFrame(pipe.write(), big); });
  const auto got = readFrame(pipe.read());
  writer.join();
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(*got, big);
}

TEST(WorkerProtocol, TruncatedLengthIsAnError) {
  Pipe pipe;
  pipe.writeRaw(std::string("\x05\x00", 2));
  pipe.closeWrite();
  try {
    readFrame(pipe.read());
    FAIL() << "a frame cut inside its length was accepted";
  } catch (const ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("2 of 4 bytes"), std::string::npos) << e.what();
  }
}

TEST(WorkerProtocol, TruncatedPayloadIsAnError) {
  Pipe pipe;
  pipe.writeRaw(lengthPrefix(10) + "abc");
  pipe.closeWrite();
  try {
    readFrame(pipe.read());
    FAIL() << "a frame cut inside its payload was accepted";
  } catch (const ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("3 of 10 bytes"), std::string::npos) << e.what();
  }
}

TEST(WorkerProtocol, OversizeLengthIsRejectedBeforeReadingThePayload) {
  Pipe pipe;
  pipe.writeRaw(lengthPrefix(0xffffffffu));  // no payload follows: reading it would block
  try {
    readFrame(pipe.read());
    FAIL() << "a 4 GiB frame was accepted";
  } catch (const ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("past the limit of " + std::to_string(kMaxFrameBytes)), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(encodeFrame(std::string(101, 'x'), 100), ProtocolError);
  Pipe small;
  small.writeRaw(lengthPrefix(101) + std::string(101, 'x'));
  EXPECT_THROW(readFrame(small.read(), 100), ProtocolError);
}

TEST(WorkerProtocol, WritingToAClosedPipeIsAnError) {
  Pipe pipe;
  pipe.closeRead();
  // The write raises SIGPIPE: blocked for this thread, so the error is what is seen.
  sigset_t pipe_only, old;
  sigemptyset(&pipe_only);
  sigaddset(&pipe_only, SIGPIPE);
  pthread_sigmask(SIG_BLOCK, &pipe_only, &old);
  EXPECT_THROW(writeFrame(pipe.write(), "x"), ProtocolError);
  const struct timespec zero {};
  sigtimedwait(&pipe_only, nullptr, &zero);
  pthread_sigmask(SIG_SETMASK, &old, nullptr);
}

TEST(WorkerProtocol, DecoderSplitsAStreamReadInPieces) {
  const std::string stream = encodeFrame("first") + encodeFrame("") + encodeFrame("third frame");
  FrameDecoder decoder;
  std::vector<std::string> frames;
  for (char c : stream) {  // one byte at a time: the worst split there is
    decoder.append(&c, 1);
    while (auto frame = decoder.next()) frames.push_back(*frame);
  }
  EXPECT_EQ(frames, (std::vector<std::string>{"first", "", "third frame"}));
  EXPECT_FALSE(decoder.partial());
  decoder.append("\x09\x00", 2);
  EXPECT_FALSE(decoder.next().has_value());
  EXPECT_TRUE(decoder.partial());

  FrameDecoder strict(8);
  const std::string too_big = lengthPrefix(9);
  strict.append(too_big.data(), too_big.size());
  EXPECT_THROW(strict.next(), ProtocolError);
}

TEST(WorkerProtocol, RequestMessagesCarryTheirType) {
  EXPECT_EQ(pingRequest(), R"({"type":"ping"})");
  EXPECT_EQ(buildRequestMessage(R"({"urdf":"x"})"), R"({"request":{"urdf":"x"},"type":"build"})");
  EXPECT_ANY_THROW(buildRequestMessage("not json"));
}

}  // namespace
}  // namespace robodiff::workers
